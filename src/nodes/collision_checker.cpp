// The collision_checker node (docs/design.md).
#include <ros/ros.h>

#include "bvh_collision/ros/collision_checker_node.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "collision_checker");
  // These handles outlive the node object: when the last NodeHandle goes, roscpp shuts down and
  // rosconsole drops every later message, including the start-up error below.
  ros::NodeHandle nh;
  ros::NodeHandle private_nh("~");
  try {
    bvh_collision::CollisionCheckerNode node(nh, private_nh);
    // Services, joint_states and timers on several threads: requests are answered side by side
    // (clouds have a thread of their own inside the node). Ready once they are served.
    ros::AsyncSpinner spinner(static_cast<std::uint32_t>(node.parameters().service_threads));
    spinner.start();
    node.mark_ready();
    ros::waitForShutdown();
  } catch (const bvh_collision::NodeStartupError& e) {
    ROS_FATAL_STREAM("collision_checker cannot start: " << e.what());
    return 1;
  }
  return 0;
}
