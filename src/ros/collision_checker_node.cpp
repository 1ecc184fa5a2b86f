#include "bvh_collision/ros/collision_checker_node.h"

#include <cmath>

#include <ros/console.h>

namespace bvh_collision {

NodeParameters read_node_parameters(const ros::NodeHandle& private_nh) {
  NodeParameters p;
  private_nh.param<std::string>("world_frame", p.world_frame, "");
  if (!private_nh.param("resolution", p.resolution, p.resolution)) {
    // A parameter of the wrong type reads as "not set" in roscpp; say so rather than ignore it.
    if (private_nh.hasParam("resolution")) {
      throw NodeStartupError("parameter ~resolution must be a number");
    }
  }
  if (!std::isfinite(p.resolution) || p.resolution <= 0.0) {
    throw NodeStartupError("parameter ~resolution must be a positive number of metres, got " +
                           std::to_string(p.resolution));
  }
  return p;
}

CollisionCheckerNode::CollisionCheckerNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(std::move(nh)), private_nh_(std::move(private_nh)) {
  params_ = read_node_parameters(private_nh_);
  std::string xml;
  if (!nh_.getParam("robot_description", xml)) {
    throw NodeStartupError("parameter '" + nh_.resolveName("robot_description") +
                           "' is not set (or is not a string): it must hold the robot's URDF");
  }
  try {
    model_ = parse_robot_description(xml);
  } catch (const RobotDescriptionError& e) {
    throw NodeStartupError("parameter '" + nh_.resolveName("robot_description") + "': " + e.what());
  }
  summary_ = summarize(*model_);
  if (params_.world_frame.empty()) params_.world_frame = summary_.root_link;
  ROS_INFO_STREAM("collision_checker: " << summary_.to_string() << "; world frame '"
                                        << params_.world_frame << "', octree resolution "
                                        << params_.resolution << " m");
  publish_status();  // last: once these are set, the node is up
}

void CollisionCheckerNode::publish_status() {
  private_nh_.setParam("world_frame", params_.world_frame);
  private_nh_.setParam("robot/name", summary_.name);
  private_nh_.setParam("robot/root_link", summary_.root_link);
  private_nh_.setParam("robot/links", static_cast<int>(summary_.links));
  private_nh_.setParam("robot/joints", static_cast<int>(summary_.joints));
  private_nh_.setParam("robot/collision_elements", static_cast<int>(summary_.collision_elements));
}

}  // namespace bvh_collision
