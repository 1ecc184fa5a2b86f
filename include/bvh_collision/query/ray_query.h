// The first body along a ray (CollisionChecker::cast_ray): the result.
#pragma once

#include <limits>
#include <string>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// The first body along a ray: a link, a collision object, or an occupied voxel.
struct RayCastResult {
  bool hit = false;
  double distance = std::numeric_limits<double>::infinity();  // along the ray from its origin
  Vec3 point = Vec3::Zero();
  int link = -1;           // the link hit, or -1
  std::string object;      // the object hit, or empty
  bool octree = false;     // an occupied voxel was hit
};

}  // namespace bvh_collision
