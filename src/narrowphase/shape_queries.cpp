// One shape alone: point, ray and extent (narrowphase/shape_queries.h).
#include "bvh_collision/narrowphase/shape_queries.h"

#include <algorithm>
#include <cmath>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/primitives.h"

namespace bvh_collision {

bool shape_holds_point(const ShapeRef& shape, const Transform& pose, const Vec3& p, double padding) {
  const auto local = [&] { return Vec3(pose.R.transpose() * (p - pose.t)); };
  if (shape.mesh == nullptr) {
    const Vec3 q = local();
    return (closest_point(shape.primitive, q) - q).norm() <= padding;
  }
  // The distance query stops beyond its bound: one step above the padding keeps "exactly at".
  // (The point goes to the mesh frame only for the containment test, as the self filter did.)
  const double reach = std::nextafter(padding, std::numeric_limits<double>::infinity());
  if (point_distance(*shape.mesh, pose, p, reach).distance <= padding) return true;
  return shape.mesh->closed() && contains_point(*shape.mesh, local());
}

double shape_ray_entry(const ShapeRef& shape, const Transform& pose, const Vec3& origin, const Vec3& unit, double length) {
  if (shape.mesh == nullptr) {
    const Mat3 Rt = pose.R.transpose();
    return ray_entry(shape.primitive, Rt * (origin - pose.t), Rt * unit, length);
  }
  const RayHit hit = raycast(*shape.mesh, pose, origin, unit, length);
  return hit.hit ? hit.distance : std::numeric_limits<double>::infinity();
}

void extend_by_shape(const BodyShape& s, Aabb& box) {
  if (s.shape.mesh == nullptr) {
    const double r = bounding_radius(s.shape.primitive);
    box.extend(s.origin.t - Vec3::Constant(r));
    box.extend(s.origin.t + Vec3::Constant(r));
    return;
  }
  for (const Triangle& t : s.shape.mesh->triangles()) {
    for (int k = 0; k < 3; ++k) box.extend(s.origin * t[k]);
  }
}

double shape_reach(const BodyShape& s, const Vec3& c) {
  if (s.shape.mesh == nullptr) return (s.origin.t - c).norm() + bounding_radius(s.shape.primitive);
  double r = 0.0;
  for (const Triangle& t : s.shape.mesh->triangles()) {
    for (int k = 0; k < 3; ++k) r = std::max(r, (s.origin * t[k] - c).norm());
  }
  return r;
}

}  // namespace bvh_collision
