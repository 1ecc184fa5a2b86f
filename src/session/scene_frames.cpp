// The frames of a scene placed around the robot (session/scene_frames.h).
#include "bvh_collision/session/scene_frames.h"

#include <vector>

#include "bvh_collision/robot/allowed_collision_matrix.h"

namespace bvh_collision {

SceneFrameLookup robot_scene_frames(const RobotModel& model, const std::string& srdf_xml, const double* state) {
  std::vector<Transform> poses;
  forward_kinematics(model, state, poses);
  std::string mount;
  if (!srdf_xml.empty()) {
    for (const SrdfVirtualJoint& v : parse_srdf(srdf_xml, &model).virtual_joints) {
      if (v.child_link == model.links()[model.root_link()].name) mount = v.parent_frame;
    }
  }
  return [&model, poses, mount](const std::string& frame) -> std::optional<Transform> {
    if ((!mount.empty() && frame == mount) || (frame == "world" && model.link_index(frame) < 0)) return Transform::Identity();
    const int l = model.link_index(frame);
    if (l < 0) return std::nullopt;
    return poses[static_cast<std::size_t>(l)];
  };
}

}  // namespace bvh_collision
