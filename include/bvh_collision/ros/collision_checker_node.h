// The collision_checker node: reads its parameters and the robot description, and (in later
// issues) serves the queries of DESIGN.md section 4. Construction throws NodeStartupError when
// the node cannot run, with a message that says why; main() prints it and exits non-zero.
#pragma once

#include <stdexcept>
#include <string>

#include <ros/node_handle.h>

#include "bvh_collision/robot/robot_description.h"

namespace bvh_collision {

class NodeStartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The node's private parameters (DESIGN.md section 4) that are in use so far.
struct NodeParameters {
  std::string world_frame;  // empty until resolved: then the URDF root link
  double resolution = 0.02;
};

// Reads and validates the private parameters; throws NodeStartupError on a bad value.
NodeParameters read_node_parameters(const ros::NodeHandle& private_nh);

class CollisionCheckerNode {
 public:
  CollisionCheckerNode(ros::NodeHandle nh, ros::NodeHandle private_nh);

  const RobotSummary& robot_summary() const { return summary_; }
  const NodeParameters& parameters() const { return params_; }

 private:
  // Publishes what was loaded as private parameters (~robot/..., ~world_frame), so that tools
  // and tests can see that the node is up and what it understood.
  void publish_status();

  ros::NodeHandle nh_;
  ros::NodeHandle private_nh_;
  NodeParameters params_;
  std::shared_ptr<urdf::ModelInterface> model_;
  RobotSummary summary_;
};

}  // namespace bvh_collision
