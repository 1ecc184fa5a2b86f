// What test_scene_checker.cpp and test_scene_motion.cpp (one binary) share: panda with the node's
// proxy levels, and the exact oracles of a state.
#pragma once

#include "bvh_collision/query/collision_checker.h"
#include "checker_fixtures.h"

namespace bvh_collision::scene_test {

// Panda as MoveIt sets it up, with the node's proxy levels.
inline const CollisionChecker& panda() { return test::panda_with_proxies(); }

// The smallest distance less padding over self pairs and obstacles (<= 0: in collision), exact.
inline double exact_clearance(const CollisionChecker& checker, const double* q, const Environment& env) {
  SelfCollisionRequest self;
  self.distance = true;
  const SelfCollisionResult s = checker.check_self(q, self);
  if (s.collision) return 0.0;
  EnvironmentRequest request;
  request.distance = true;
  request.contacts = false;
  const EnvironmentResult e = checker.check_environment(q, env, request);
  if (e.collision) return 0.0;
  return std::min(s.min_distance, e.min_distance);  // panda has no padding here
}

inline bool exact_collides(const CollisionChecker& checker, const double* q, const Environment& env) {
  EnvironmentRequest request;
  request.contacts = false;
  return checker.check_self(q).collision || checker.check_environment(q, env, request).collision;
}

}  // namespace bvh_collision::scene_test
