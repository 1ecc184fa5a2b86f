// Conservative advancement with exact distances: a certified motion check written independently
// of the engine (query/scene_checker.h, behind CollisionChecker::check_motion), which tests and
// benchmarks hold the engine's answers against. Over a step ds every point of link L moves at most
// ds * M_L (CollisionChecker::link_speed); a self pair closes by at most the sum of its two
// links', an obstacle gap by one link's. So a step below the clearance over the fastest closing
// rate cannot hide a collision: the motion advances by such steps from its start, each from the
// exact clearance of the state it reached, until it reaches the goal or a state within
// max(tolerance, min_clearance) of collision.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "bvh_collision/query/collision_checker.h"

namespace bvh_collision::test {

// The exact clearance of `state` (its distance to everything checked, less padding; a self
// pair's padding counted twice at the largest), or nothing when it collides.
inline std::optional<double> exact_clearance(const CollisionChecker& checker, const double* state, const Environment& env,
                                             const MotionRequest& request, double max_padding) {
  double gap = std::numeric_limits<double>::infinity();
  if (request.self) {
    SelfCollisionRequest r;
    r.distance = true;
    const SelfCollisionResult result = checker.check_self(state, r);
    if (result.collision) return std::nullopt;
    if (std::isfinite(result.min_distance)) gap = std::min(gap, result.min_distance - 2.0 * max_padding);
  }
  if (request.environment) {
    EnvironmentRequest r;
    r.distance = true;
    r.root_pose = request.root_pose;
    const EnvironmentResult result = checker.check_environment(state, env, r);
    if (result.collision) return std::nullopt;
    if (std::isfinite(result.min_distance)) gap = std::min(gap, result.min_distance - max_padding);
  }
  return gap;
}

// The motion from start to goal certified by advancement (request.resolution is ignored; states
// checked counts the states whose clearance was taken).
inline MotionResult advancement_motion(const CollisionChecker& checker, const double* start, const double* goal,
                                       const Environment& env, const MotionRequest& request = {}) {
  const std::size_t n = checker.model().variable_count();
  double speed = 0.0, max_padding = 0.0;
  for (std::size_t l = 0; l < checker.model().links().size(); ++l) {
    speed = std::max(speed, checker.link_speed(static_cast<int>(l), start, goal));
    max_padding = std::max(max_padding, checker.link_padding(static_cast<int>(l)));
  }
  const double closing = (request.self ? 2.0 : 1.0) * speed;
  const double stop = std::max(request.tolerance, request.min_clearance);
  std::vector<double> q(n);
  MotionResult result;
  double s = 0.0;
  while (result.states_checked < request.max_states) {
    ++result.states_checked;
    for (std::size_t j = 0; j < n; ++j) q[j] = s >= 1.0 ? goal[j] : start[j] + s * (goal[j] - start[j]);
    const std::optional<double> gap = exact_clearance(checker, q.data(), env, request, max_padding);
    if (!gap || *gap <= stop) {  // in collision, or within the tolerance of it
      result.certified = true;
      result.colliding_fraction = s;
      return result;
    }
    result.last_valid_fraction = s;
    if (s >= 1.0) {
      result.valid = result.certified = true;
      return result;
    }
    // 0.99: the clearance and the rates are exact bounds; room for their rounding.
    s = closing > 0.0 ? std::min(1.0, s + 0.99 * *gap / closing) : 1.0;
  }
  result.message = "not certified after " + std::to_string(request.max_states) + " states";
  return result;
}

}  // namespace bvh_collision::test
