// The self filter: a scan's points on the robot and in its shadow are not obstacles.
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/tree_walk.h"
#include "bvh_collision/narrowphase/shape_queries.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"
#include "bvh_collision/geometry/in_chunks.h"

namespace bvh_collision {
namespace {

// A link as the filter sees it for one scan: pose and bounding sphere in the scan's frame.
struct LinkInScan {
  int link = -1;
  Transform pose;
  Vec3 centre = Vec3::Zero();
  double radius = 0.0;
  double padding = 0.0;  // the robot's links: the filter's; carried objects: theirs
  bool holds_sensor = false;
};

// Does the segment origin + s * unit, 0 <= s <= length, meet the ball?
bool segment_meets_ball(const Vec3& origin, const Vec3& unit, double length, const Vec3& centre, double radius) {
  const double s = std::clamp((centre - origin).dot(unit), 0.0, length);
  return (origin + s * unit - centre).squaredNorm() <= radius * radius;
}

// What a link's proxy (narrowphase/link_proxy.h) says of a point and a padding: -1, the point is
// farther than the padding from the link (no leaf sphere grown by the padding holds it); 1, it is
// within the padding (a leaf sphere grown by padding - h holds it, h >= the distance from any
// sphere point to the link, so padding >= h is needed); 0, the exact test must tell. The spheres
// stay in the link frame and the point goes there once.
int proxy_point_verdict(const LinkProxy& proxy, const Transform& pose, const Vec3& p, double padding) {
  if (proxy.empty()) return -1;
  const std::vector<ProxySphere>& s = proxy.spheres();
  const Vec3 local = pose.R.transpose() * (p - pose.t);
  const double margin = proxy_pose_margin(proxy, pose) + pose_margin(p.norm());
  const bool can_accept = padding >= proxy.hausdorff_bound();
  const double accept = padding - proxy.hausdorff_bound() - margin;
  int verdict = -1;
  skip_walk(static_cast<std::int32_t>(s.size()), [&](std::int32_t i) { return s[i].skip; }, [&](std::int32_t i, bool leaf) {
    const double d2 = (s[i].center - local).squaredNorm();
    const double reach = grown_radius(s[i].radius + padding + margin);
    if (d2 > reach * reach) return Visit::kSkip;
    if (!leaf) return Visit::kEnter;
    verdict = 0;
    const double inside = s[i].radius + accept;
    if (!(can_accept && inside > 0.0 && d2 <= inside * inside)) return Visit::kSkip;
    verdict = 1;
    return Visit::kStop;
  });
  return verdict;
}

}  // namespace

bool CollisionChecker::point_on_link(int link, const Transform& pose, const Vec3& p, double padding) const {
  // "On or within": a point exactly at the padding distance counts.
  return compound_holds_point(m_->compound(link), pose, p, padding);
}

double CollisionChecker::ray_meets_link(int link, const Transform& pose, const Vec3& origin, const Vec3& unit,
                                        double length) const {
  return compound_ray_entry(m_->compound(link), pose, origin, unit, length);
}

FilteredScan CollisionChecker::filter_scan(const double* state, const std::vector<ScanPoint>& points,
                                           const ScanPoint& sensor, double padding, const Transform& root_pose,
                                           std::optional<double> carried_padding) const {
  for (const double pad : {padding, carried_padding.value_or(padding)}) {
    if (!(pad >= 0.0) || !std::isfinite(pad)) {
      throw std::invalid_argument("self filter: padding must be finite and >= 0, got " + std::to_string(pad));
    }
  }
  if (!sensor.allFinite()) throw std::invalid_argument("self filter: the sensor origin is not finite");
  if (!is_rigid(root_pose)) throw std::invalid_argument("self filter: the root pose is not a finite rigid transform");
  std::vector<Transform> poses;
  m_->kinematics().compute(state, poses);
  const Vec3 origin = sensor.cast<double>();
  std::vector<LinkInScan> links;
  for (std::size_t l = 0; l < m_->shapes().size(); ++l) {
    if (m_->shapes()[l].empty()) continue;
    const int link = static_cast<int>(l);
    poses[l] = root_pose * poses[l];
    const double pad = l < m_->robot_link_count() ? padding : carried_padding.value_or(padding);
    links.push_back({link, poses[l], poses[l] * m_->bounds()[l].center, m_->bounds()[l].radius, pad,
                     point_on_link(link, poses[l], origin, pad)});
  }
  // Where proxies are built, they settle most points near a link without the exact test, with
  // the same answers: the coarsest level whose spheres lie within the padding of their links
  // (accepts and rejects), else the finest (rejects only).
  const std::vector<ProxyLevel>& levels = a_->proxy_levels();
  // (A point is an exact obstacle and the padding the room: tolerance_policy.h's rule.)
  const ProxyLevel* proxies = a_->proxies_for(proxy_use({padding, Counterpart::kObject}).decide_up_to);
  if (proxies == nullptr && !levels.empty()) proxies = &levels.front();
  // One point: on the robot, in its shadow, or an obstacle; a ray that clears only ends the
  // padding of the link it first meets before it.
  auto classify = [&](const ScanPoint& point, FilteredScan& out) {
    const Vec3 p = point.cast<double>();
    const Vec3 d = p - origin;
    const double length = d.norm();
    if (!p.allFinite() || !(length > 0.0)) {
      out.obstacles.push_back(point);  // insert_scan skips and counts these
      return;
    }
    const Vec3 unit = d / length;
    bool on_robot = false;
    double first = length, first_padding = padding;
    for (const LinkInScan& v : links) {
      const double reach = v.radius + v.padding;
      if (!on_robot && (p - v.centre).squaredNorm() <= reach * reach) {
        const int verdict = proxies ? proxy_point_verdict(proxies->links[v.link], v.pose, p, v.padding) : 0;
        on_robot = verdict > 0 || (verdict == 0 && point_on_link(v.link, v.pose, p, v.padding));
      }
      if (!v.holds_sensor && segment_meets_ball(origin, unit, first, v.centre, v.radius)) {
        const double entry = ray_meets_link(v.link, v.pose, origin, unit, first);
        if (entry < first) first = entry, first_padding = v.padding;
      }
    }
    if (!on_robot && first >= length) {
      out.obstacles.push_back(point);
      return;
    }
    ++(on_robot ? out.on_robot : out.shadowed);
    if (first - first_padding > 0.0) out.clear_only.push_back((origin + unit * (first - first_padding)).cast<float>());
  };
  auto filter_chunk = [&](std::size_t begin, std::size_t end, FilteredScan& part) {
    for (std::size_t i = begin; i < end; ++i) classify(points[i], part);
  };
  std::vector<FilteredScan> parts = detail::in_chunks<FilteredScan>(points.size(), filter_chunk);
  FilteredScan all = std::move(parts.front());
  for (std::size_t w = 1; w < parts.size(); ++w) {
    all.obstacles.insert(all.obstacles.end(), parts[w].obstacles.begin(), parts[w].obstacles.end());
    all.clear_only.insert(all.clear_only.end(), parts[w].clear_only.begin(), parts[w].clear_only.end());
    all.on_robot += parts[w].on_robot;
    all.shadowed += parts[w].shadowed;
  }
  return all;
}

}  // namespace bvh_collision
