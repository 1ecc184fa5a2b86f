// Known objects are not voxels (world/object_filter.h).
#include "bvh_collision/world/object_filter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "bvh_collision/narrowphase/shape_queries.h"
#include "bvh_collision/geometry/in_chunks.h"

namespace bvh_collision {
namespace {

// An object as the filter sees it: its exact shape and its bounding ball in the world.
struct ObjectInScan {
  ShapeRef shape;
  Transform pose;
  Vec3 centre = Vec3::Zero();
  double radius = 0.0;
  bool holds_sensor = false;
};

// Does the segment origin + s * unit, 0 <= s <= length, come within `radius` of `centre`?
bool segment_near_ball(const Vec3& origin, const Vec3& unit, double length, const Vec3& centre, double radius) {
  const double s = std::clamp((centre - origin).dot(unit), 0.0, length);
  return (origin + s * unit - centre).squaredNorm() <= radius * radius;
}

struct Part {
  std::vector<ScanPoint> kept, clear_only;
  std::size_t on_objects = 0;
};

}  // namespace

void filter_objects(const ObjectList& objects, const ScanPoint& sensor, double padding,
                    FilteredScan& scan) {
  if (!(padding >= 0.0) || !std::isfinite(padding)) {
    throw std::invalid_argument("object filter: padding must be finite and >= 0, got " + std::to_string(padding));
  }
  if (!sensor.allFinite()) throw std::invalid_argument("object filter: the sensor origin is not finite");
  if (objects.empty() || scan.obstacles.empty()) return;
  const Vec3 origin = sensor.cast<double>();
  std::vector<ObjectInScan> solids;
  for (const CollisionObject& o : objects) {
    const ShapeRef shape = exact_shape_of(o);
    solids.push_back({shape, o.pose, o.pose * o.bound_center, o.bound_radius,
                      shape_holds_point(shape, o.pose, origin, padding)});
  }
  auto classify = [&](const ScanPoint& point, Part& out) {
    const Vec3 p = point.cast<double>();
    const double length = (p - origin).norm();
    if (!p.allFinite() || !(length > 0.0)) return out.kept.push_back(point);  // insert_scan counts these
    bool on_object = false;
    for (const ObjectInScan& s : solids) {
      const double reach = s.radius + padding;
      if ((p - s.centre).squaredNorm() <= reach * reach && shape_holds_point(s.shape, s.pose, p, padding)) {
        on_object = true;
        break;
      }
    }
    if (!on_object) return out.kept.push_back(point);
    ++out.on_objects;
    const Vec3 unit = (p - origin) / length;
    double first = length;
    for (const ObjectInScan& s : solids) {
      if (s.holds_sensor || !segment_near_ball(origin, unit, first, s.centre, s.radius)) continue;
      first = std::min(first, shape_ray_entry(s.shape, s.pose, origin, unit, first));
    }
    if (first - padding > 0.0) out.clear_only.push_back((origin + unit * (first - padding)).cast<float>());
  };
  const std::vector<ScanPoint>& points = scan.obstacles;
  std::vector<Part> parts = detail::in_chunks<Part>(points.size(), [&](std::size_t begin, std::size_t end, Part& part) {
    for (std::size_t i = begin; i < end; ++i) classify(points[i], part);
  });
  std::vector<ScanPoint> kept = std::move(parts.front().kept);
  for (std::size_t w = 0; w < parts.size(); ++w) {
    if (w > 0) kept.insert(kept.end(), parts[w].kept.begin(), parts[w].kept.end());
    scan.clear_only.insert(scan.clear_only.end(), parts[w].clear_only.begin(), parts[w].clear_only.end());
    scan.on_objects += parts[w].on_objects;
  }
  scan.obstacles = std::move(kept);
}

}  // namespace bvh_collision
