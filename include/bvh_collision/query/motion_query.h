// Motions between two states (CollisionChecker::check_motion): request and result.
#pragma once

#include <cstddef>
#include <string>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// The straight joint-space motion from start to goal (docs/design.md, check_motion).
struct MotionRequest {
  bool self = true, environment = true;
  // > 0: states every `resolution` of joint motion (max norm over joints, rad or m), both ends
  // included. 0: certified: intervals of the motion proven free whole (query/scene_checker.h), so
  // that no collision hides between the states checked.
  double resolution = 0.0;
  double tolerance = 0.0;     // docs/design.md
  Transform root_pose;        // the root link in the world frame
  // Certified: a motion answered free stays farther than this from every collision; one that
  // comes within it may count as colliding (an exact contact can be approached, never proven
  // apart: this bounds the work near one, and is a tolerance of its own). A self pair or link
  // that is closer than twice this at one of the motion's ends (a valid state a planner must
  // reach and leave) keeps at least a quarter of its clearance there instead (query/scene_checker.h).
  double min_clearance = 1e-5;
  // Certified: beyond this many states checked the motion is not certified (invalid, with a
  // message).
  std::size_t max_states = 20000;
};

struct MotionResult {
  bool valid = false;
  double last_valid_fraction = 0.0;  // the end of the stretch from 0 proven free (1 when valid)
  // Where the collision was found (-1 when none): a state that collides, or the middle of an
  // interval of the motion that comes within the tolerance of a collision somewhere.
  double colliding_fraction = -1.0;
  // The states at which the robot was posed and tested: at a joint step, each step's state;
  // certified, the two ends and one state per interval (its midpoint); 0 when the answer came
  // from this thread's memory of the same motion, or of one that contains it.
  std::size_t states_checked = 0;
  bool certified = false;    // the whole motion (or up to the collision) was certified
  std::string message;       // why a certified check gave up, when it did
};

}  // namespace bvh_collision
