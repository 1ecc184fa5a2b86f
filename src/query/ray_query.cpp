// CollisionChecker::cast_ray: the first link, collision object or occupied voxel along a ray.
#include <stdexcept>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/narrowphase/shape_queries.h"

namespace bvh_collision {
namespace {

// Where the ray first meets an object, or infinity.
double ray_meets_object(const CollisionObject& object, const Vec3& origin, const Vec3& unit, double length) {
  return shape_ray_entry(shape_of(object), object.pose, origin, unit, length);
}

}  // namespace

RayCastResult CollisionChecker::cast_ray(const double* state, const Environment& env, const Vec3& origin,
                                         const Vec3& direction, double max_range, const Transform& root_pose) const {
  require_carried(env);
  require_finite_state(state, "ray");
  if (!origin.allFinite()) throw std::invalid_argument("ray: the origin is not finite");
  const double norm = direction.norm();
  if (!direction.allFinite() || !(norm > 0.0)) throw std::invalid_argument("ray: the direction must be finite and not zero");
  if (std::isnan(max_range)) throw std::invalid_argument("ray: max_range is NaN");
  if (!is_rigid(root_pose)) throw std::invalid_argument("ray: the root pose is not a finite rigid transform");
  const Vec3 unit = direction / norm;
  RayCastResult result;
  result.distance = max_range > 0.0 ? max_range : std::numeric_limits<double>::infinity();
  std::vector<Transform> poses;
  m_->kinematics().compute(state, poses);
  for (std::size_t l = 0; l < m_->shapes().size(); ++l) {
    if (m_->shapes()[l].empty()) continue;
    const double d = ray_meets_link(static_cast<int>(l), root_pose * poses[l], origin, unit, result.distance);
    if (std::isfinite(d) && d <= result.distance && (!result.hit || d < result.distance)) {
      result = {true, d, origin + d * unit, static_cast<int>(l), std::string(), false};
    }
  }
  for (const CollisionObject& object : env.objects()) {
    const double d = ray_meets_object(object, origin, unit, result.distance);
    if (std::isfinite(d) && d <= result.distance && (!result.hit || d < result.distance)) {
      result = {true, d, origin + d * unit, -1, object.id, false};
    }
  }
  const double octree_range = std::isfinite(result.distance) ? result.distance : 1e9;
  if (const auto hit = env.octree().cast_ray(origin, unit, octree_range); hit && (!result.hit || hit->distance < result.distance)) {
    result = {true, hit->distance, hit->point, -1, std::string(), true};
  }
  if (!result.hit) result.distance = std::numeric_limits<double>::infinity();
  return result;
}

}  // namespace bvh_collision
