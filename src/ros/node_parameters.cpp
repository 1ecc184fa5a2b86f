// The node's private parameters: read, checked, and explained when wrong.
#include <cmath>
#include <cstdlib>

#include "bvh_collision/ros/collision_checker_node.h"

namespace bvh_collision {

namespace {

// roscpp reads a parameter of the wrong type as "not set"; say so rather than ignore it.
template <class T>
void read(const ros::NodeHandle& nh, const std::string& name, T& value, const char* expected) {
  if (!nh.param(name, value, value) && nh.hasParam(name)) {
    throw NodeStartupError("parameter ~" + name + " must be " + expected);
  }
}

double read_number(const ros::NodeHandle& nh, const std::string& name, double value, bool positive) {
  read(nh, name, value, "a number");  // roscpp reads an int parameter as a double too
  if (!std::isfinite(value) || (positive ? value <= 0.0 : value < 0.0)) {
    throw NodeStartupError("parameter ~" + name + " must be a " + (positive ? "positive" : "non-negative") +
                           " number, got " + std::to_string(value));
  }
  return value;
}

// A whole number in [1, most] (read as a double: a value too large for an int must be refused,
// not wrapped).
std::size_t read_count(const ros::NodeHandle& nh, const std::string& name, std::size_t value, double most) {
  double v = static_cast<double>(value);
  if (nh.hasParam(name) && !nh.getParam(name, v)) throw NodeStartupError("parameter ~" + name + " must be a number");
  if (!(v >= 1.0 && v <= most) || v != std::floor(v)) {
    throw NodeStartupError("parameter ~" + name + " must be a whole number from 1 to " + std::to_string(std::size_t(most)) +
                           ", got " + std::to_string(v));
  }
  return static_cast<std::size_t>(v);
}

void read_limits(const ros::NodeHandle& nh, NodeParameters& p) {
  constexpr double kMost = 1e12;  // any count a machine could hold; the defaults are the real limits
  Limits& l = p.limits;
  l.motion_states = read_count(nh, "max_motion_states", l.motion_states, kMost);
  l.batch_states = read_count(nh, "max_batch_states", l.batch_states, kMost);
  l.cloud_points = read_count(nh, "max_cloud_points", l.cloud_points, kMost);
  l.ray_voxels = read_count(nh, "max_ray_voxels", l.ray_voxels, kMost);
  l.object_triangles = read_count(nh, "max_object_triangles", l.object_triangles, kMost);
  l.robot_links = read_count(nh, "max_robot_links", l.robot_links, kMost);
  l.checked_pairs = read_count(nh, "max_checked_pairs", l.checked_pairs, kMost);
  // A ray may cross max_range / resolution voxels: refused here rather than on every cloud.
  try {
    check_limit("~max_range " + std::to_string(p.max_range) + " m at ~resolution " + std::to_string(p.resolution) +
                    " m: a ray with its voxels",
                std::ceil(p.max_range / p.resolution), l.ray_voxels, "max_ray_voxels");
  } catch (const LimitExceeded& e) {
    throw NodeStartupError(e.what());
  }
}

double read_probability(const ros::NodeHandle& nh, const std::string& name, double value) {
  value = read_number(nh, name, value, true);
  if (value >= 1.0) throw NodeStartupError("parameter ~" + name + " must be a probability in (0, 1)");
  return value;
}

std::optional<Vec3> read_point(const ros::NodeHandle& nh, const std::string& name) {
  if (!nh.hasParam(name)) return std::nullopt;
  std::vector<double> v;
  if (!nh.getParam(name, v) || v.size() != 3 || !Vec3(v[0], v[1], v[2]).allFinite()) {
    throw NodeStartupError("parameter ~" + name + " must be a list of three finite numbers [x, y, z]");
  }
  return Vec3(v[0], v[1], v[2]);
}

void read_workspace(const ros::NodeHandle& nh, NodeParameters& p) {
  p.workspace_min = read_point(nh, "workspace_min");
  p.workspace_max = read_point(nh, "workspace_max");
  if (p.workspace_min.has_value() != p.workspace_max.has_value()) {
    throw NodeStartupError("parameters ~workspace_min and ~workspace_max must be set together");
  }
  if (p.workspace_min && (p.workspace_min->array() > p.workspace_max->array()).any()) {
    throw NodeStartupError("parameter ~workspace_min must not exceed ~workspace_max on any axis");
  }
}

void read_link_padding(const ros::NodeHandle& nh, NodeParameters& p) {
  if (!nh.hasParam("link_padding")) return;
  if (!nh.getParam("link_padding", p.link_padding)) {
    throw NodeStartupError("parameter ~link_padding must be a map from link name to padding (m)");
  }
  for (const auto& [link, padding] : p.link_padding) {
    if (!std::isfinite(padding) || padding < 0.0) {
      throw NodeStartupError("parameter ~link_padding/" + link + " must be a non-negative number");
    }
  }
}

// Levels below a millimetre would take minutes and gigabytes to build (the sphere count grows
// as 1/e^2 on a surface); more than a handful buys nothing.
void read_proxy_levels(const ros::NodeHandle& nh, NodeParameters& p) {
  constexpr double kFinest = 0.001, kCoarsest = 1.0;
  constexpr std::size_t kMostLevels = 8;
  if (!nh.hasParam("proxy_levels")) return;
  if (!nh.getParam("proxy_levels", p.proxy_levels)) {
    throw NodeStartupError("parameter ~proxy_levels must be a list of numbers (m), e.g. [0.01, 0.02]");
  }
  if (p.proxy_levels.size() > kMostLevels) {
    throw NodeStartupError("parameter ~proxy_levels: at most " + std::to_string(kMostLevels) + " levels, got " +
                           std::to_string(p.proxy_levels.size()));
  }
  for (const double level : p.proxy_levels) {
    if (!(level >= kFinest && level <= kCoarsest)) {
      throw NodeStartupError("parameter ~proxy_levels: every level must lie in [0.001, 1] m, got " + std::to_string(level));
    }
  }
}

void read_no_return(const ros::NodeHandle& nh, NodeParameters& p) {
  if (nh.hasParam("clear_no_return") && !nh.getParam("clear_no_return", p.clear_no_return)) {
    throw NodeStartupError("parameter ~clear_no_return must be a boolean");
  }
  read(nh, "camera_info", p.camera_info_topic, "a string (a sensor_msgs/CameraInfo topic; empty for none)");
  if (!nh.hasParam("camera_intrinsics")) return;
  std::vector<double> k;
  const PinholeCamera camera = nh.getParam("camera_intrinsics", k) && k.size() == 4 ? PinholeCamera{k[0], k[1], k[2], k[3]}
                                                                                   : PinholeCamera{};
  if (!camera.valid()) {
    throw NodeStartupError("parameter ~camera_intrinsics must be [fx, fy, cx, cy] (pixels), finite, fx and fy non-zero");
  }
  p.camera_intrinsics = camera;
}

}  // namespace

OccupancyModel NodeParameters::occupancy_model() const {
  OccupancyModel m;
  m.hit = log_odds(sensor_hit);
  m.miss = log_odds(sensor_miss);
  m.clamp_min = log_odds(sensor_min);
  m.clamp_max = log_odds(sensor_max);
  return m;
}

NodeParameters read_node_parameters(const ros::NodeHandle& nh) {
  NodeParameters p;
  read(nh, "world_frame", p.world_frame, "a string");
  p.resolution = read_number(nh, "resolution", p.resolution, true);
  p.padding = read_number(nh, "padding", p.padding, false);
  read_link_padding(nh, p);
  p.tolerance = read_number(nh, "tolerance", p.tolerance, false);
  p.pin_timeout = read_number(nh, "pin_timeout", p.pin_timeout, true);
  read_proxy_levels(nh, p);
  const char* ros_home = std::getenv("ROS_HOME");
  const char* home = std::getenv("HOME");
  p.proxy_cache = ros_home && *ros_home ? std::string(ros_home) : home && *home ? std::string(home) + "/.ros" : "";
  if (!p.proxy_cache.empty()) p.proxy_cache += "/bvh_collision/proxy_cache";
  read(nh, "proxy_cache", p.proxy_cache, "a string (a folder; empty for none)");
  read_workspace(nh, p);
  p.max_range = read_number(nh, "max_range", p.max_range, true);
  p.self_filter_padding = read_number(nh, "self_filter_padding", p.self_filter_padding, false);
  if (nh.hasParam("object_padding")) p.object_padding = read_number(nh, "object_padding", 0.0, false);
  read_no_return(nh, p);
  if (nh.hasParam("distance_field") && !nh.getParam("distance_field", p.distance_field)) {
    throw NodeStartupError("parameter ~distance_field must be a boolean");
  }
  p.sensor_hit = read_probability(nh, "sensor_model/hit", p.sensor_hit);
  p.sensor_miss = read_probability(nh, "sensor_model/miss", p.sensor_miss);
  p.sensor_min = read_probability(nh, "sensor_model/min", p.sensor_min);
  p.sensor_max = read_probability(nh, "sensor_model/max", p.sensor_max);
  if (p.sensor_hit <= 0.5 || p.sensor_miss >= 0.5 || p.sensor_min >= p.sensor_max) {
    throw NodeStartupError(
        "parameters ~sensor_model: hit must be above 0.5, miss below 0.5, and min below max");
  }
  read(nh, "octree_file", p.octree_file, "a string (a .bt or .ot path)");
  read(nh, "scene_file", p.scene_file, "a string (a MoveIt .scene path)");
  p.cloud_transform_timeout = read_number(nh, "cloud_transform_timeout", p.cloud_transform_timeout, false);
  p.joint_state_history = read_number(nh, "joint_state_history", p.joint_state_history, false);
  p.joint_state_lead = read_number(nh, "joint_state_lead", p.joint_state_lead, false);
  p.joint_state_timeout = read_number(nh, "joint_state_timeout", p.joint_state_timeout, false);
  p.tf_timeout = read_number(nh, "tf_timeout", p.tf_timeout, false);
  p.diagnostic_period = read_number(nh, "diagnostic_period", p.diagnostic_period, true);
  p.marker_rate = read_number(nh, "marker_rate", p.marker_rate, true);
  p.marker_alpha = read_number(nh, "marker_alpha", p.marker_alpha, true);
  if (p.marker_alpha > 1.0) {
    throw NodeStartupError("parameter ~marker_alpha must be in (0, 1], got " + std::to_string(p.marker_alpha));
  }
  p.service_threads = static_cast<int>(read_count(nh, "service_threads", p.service_threads, kMostServiceThreads));
  double nice = p.cloud_nice;
  if (nh.hasParam("cloud_nice") && !nh.getParam("cloud_nice", nice)) throw NodeStartupError("parameter ~cloud_nice must be a number");
  if (!(nice >= 0.0 && nice <= 19.0) || nice != std::floor(nice)) {
    throw NodeStartupError("parameter ~cloud_nice must be a whole number from 0 to 19, got " + std::to_string(nice));
  }
  p.cloud_nice = static_cast<int>(nice);
  read_limits(nh, p);
  return p;
}

}  // namespace bvh_collision
