// Conversions between ROS messages and the checker's plain types, with the validation that
// docs/design.md asks of every request: a malformed message gives a message that names what
// is wrong, never a crash and never a silently wrong answer.
#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Transform.h>
#include <sensor_msgs/PointCloud2.h>
#include <shape_msgs/Mesh.h>
#include <shape_msgs/SolidPrimitive.h>

#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/world/environment.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/package_resolver.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

// A request that cannot be answered; what() is the response's `error`.
class RequestError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// Joint values by name onto full state vectors (RobotModel::variable_names order).
class JointValueMap {
 public:
  explicit JointValueMap(const RobotModel& model);

  // Maps `names` to state variables. Throws RequestError for an unknown or repeated name, or a
  // fixed or floating joint. A mimic joint's column is ignored (its value follows its source),
  // and `warnings` says so.
  std::vector<int> columns(const std::vector<std::string>& names, std::vector<std::string>& warnings) const;

  // Writes one row of values (one per column) into `state`. Throws RequestError for a NaN or
  // infinite value; a value outside its joint's limits is written and reported in `warnings`
  // (the answer is still given: the planner may be probing).
  void write(const std::vector<int>& columns, const double* values, const std::vector<std::string>& names,
             std::vector<double>& state, std::vector<std::string>& warnings) const;

  // Whether a name is a joint of the model at all (joint_states from other robots are ignored).
  bool knows(const std::string& name) const;

 private:
  RobotModel model_;  // a copy: the checker it came from may be replaced (proxy levels)
  std::vector<double> lower_, upper_;
  std::vector<bool> bounded_;
};

// Sets `state` to every variable at 0 clamped into its limits: the state before joint_states.
std::vector<double> neutral_state(const RobotModel& model);

// Joins warnings into one line ("; " between them), keeping at most `max` and counting the rest.
std::string join_warnings(const std::vector<std::string>& warnings, std::size_t max = 5);

// A pose message as a rigid transform. Throws RequestError for non-finite values or a quaternion
// whose norm is not within 1e-3 of 1 (it is normalised otherwise, as tf2 does).
Transform to_transform(const geometry_msgs::Pose& pose);
Transform to_transform(const geometry_msgs::Transform& transform);
geometry_msgs::Pose to_pose_msg(const Transform& transform);

// shape_msgs as object shapes (a primitive with its message's dimension indices; cones and
// cylinders stay exact). Throw RequestError naming the problem (unknown type, wrong number of
// dimensions, a vertex index out of range...).
ObjectShape to_object_shape(const shape_msgs::SolidPrimitive& shape);
ObjectShape to_object_shape(const shape_msgs::Mesh& shape);
// A mesh file (package://, file:// or a path) read through `resolver`, scaled per axis (all zeros: 1).
ObjectShape mesh_resource_shape(const std::string& uri, const geometry_msgs::Vector3& scale,
                                const PackageResolver& resolver);

// One shape of a collision object and its pose in the object's frame.
struct PlacedShape {
  ObjectShape shape;
  Transform pose;
};
// Every shape of a SetCollisionObject request, in its order: primitives, meshes, mesh resources.
// Throws RequestError naming the field ("primitives[1]: CONE needs 2 dimensions ...") for a bad
// shape or pose, arrays whose lengths do not pair up, or no shape at all.
std::vector<PlacedShape> object_shapes(const SetCollisionObject::Request& req, const PackageResolver& resolver);

// The points of a cloud, in its own frame. Fields x, y and z must be FLOAT32 or FLOAT64 and lie
// within point_step; the data must hold height * row_step bytes. Throws RequestError otherwise.
// NaN and infinite points are kept: insertion skips and counts them.
std::vector<ScanPoint> cloud_points(const sensor_msgs::PointCloud2& cloud);

// An unorganised cloud (height 1) of FLOAT32 x, y, z points in `frame`.
sensor_msgs::PointCloud2 to_cloud_msg(const std::vector<ScanPoint>& points, const std::string& frame);

}  // namespace bvh_collision
