// The frames a scene file may name when the world is the robot's root frame (the command-line
// tool's and the Python module's world): placing a scene's objects (io/scene_file.h,
// place_in_world) with the robot in a given state.
#pragma once

#include <string>

#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

// With the robot in `state` (variable_count() values) and its root link at the world's origin:
// the root (also named "world" unless a link is so named, and the parent frame of the SRDF's
// virtual joint that holds it, when `srdf_xml` is given) and every link. The lookup refers to
// `model`, which must outlive it.
SceneFrameLookup robot_scene_frames(const RobotModel& model, const std::string& srdf_xml, const double* state);

}  // namespace bvh_collision
