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
  // included. 0: certified: each step is shorter than the clearance at its start divided by a
  // bound on how fast any point of any link moves, so no collision hides between states.
  double resolution = 0.0;
  double tolerance = 0.0;     // docs/design.md
  Transform root_pose;        // the root link in the world frame
  // Certified: a motion that comes within this of collision counts as colliding. Advancement
  // by clearance can only creep towards an exact contact, never reach it; this bounds the steps
  // (about log(clearance / min_clearance) of them near a contact) and is a tolerance of its own.
  double min_clearance = 1e-5;
  std::size_t max_states = 20000;  // certified: beyond this the motion is not certified (invalid)
};

struct MotionResult {
  bool valid = false;
  double last_valid_fraction = 0.0;  // the last state checked free before the first collision (1 when valid)
  // The state found colliding (or, at a tolerance, within it of collision); -1 when none.
  double colliding_fraction = -1.0;
  std::size_t states_checked = 0;
  bool certified = false;    // the whole motion (or up to the collision) was certified
  std::string message;       // why a certified check gave up, when it did
};

}  // namespace bvh_collision
