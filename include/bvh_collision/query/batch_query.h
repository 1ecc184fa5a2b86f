// Boolean checks of many states at once (CollisionChecker::check_batch): the request.
#pragma once

#include "bvh_collision/model/proxy_batch.h"
#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// A batch of states checked for collision, boolean (check_batch).
struct BatchRequest {
  bool self = true, environment = true;
  double tolerance = 0.0;  // docs/design.md
  Transform root_pose;     // the root link in the world frame
  // At a tolerance a proxy level fits, self checks run four states at a time in SIMD lanes
  // (model/proxy_batch.h) on this kernel; kAuto: AVX2 where the CPU has it.
  SimdPath simd = SimdPath::kAuto;
};

}  // namespace bvh_collision
