// demo_scene_publisher: what a robot's drivers would publish, for the demo (launch/demo.launch).
//   - joint_states: a fixed configuration (~positions, in ~joint_names order), at 10 Hz;
//   - tf: world -> the robot's root link (~root_link) and world -> camera, both static;
//   - obstacle_cloud: the surface of a box-shaped pillar (~pillar_center, ~pillar_size, in world)
//     as a camera at ~camera_position would see it, in the camera's frame, at ~cloud_rate Hz.
#include <cmath>
#include <string>
#include <vector>

#include <geometry_msgs/TransformStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "bvh_collision/ros/conversions.h"

namespace {

using bvh_collision::ScanPoint;

std::vector<double> vector_param(const ros::NodeHandle& nh, const std::string& name, std::vector<double> fallback) {
  nh.getParam(name, fallback);
  return fallback;
}

geometry_msgs::TransformStamped translation(const std::string& parent, const std::string& child,
                                            const std::vector<double>& xyz) {
  geometry_msgs::TransformStamped t;
  t.header.stamp = ros::Time::now();
  t.header.frame_id = parent;
  t.child_frame_id = child;
  t.transform.translation.x = xyz.at(0);
  t.transform.translation.y = xyz.at(1);
  t.transform.translation.z = xyz.at(2);
  t.transform.rotation.w = 1.0;
  return t;
}

// Points every `step` metres on the faces of an axis-aligned box.
std::vector<ScanPoint> box_surface(const Eigen::Vector3f& centre, const Eigen::Vector3f& size, float step) {
  std::vector<ScanPoint> points;
  const Eigen::Vector3f lo = centre - 0.5f * size;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int nu = std::max(1, int(std::ceil(size[u] / step))), nv = std::max(1, int(std::ceil(size[v] / step)));
    for (float side : {0.0f, 1.0f}) {
      for (int i = 0; i <= nu; ++i) {
        for (int j = 0; j <= nv; ++j) {
          ScanPoint p = lo;
          p[axis] += side * size[axis];
          p[u] += size[u] * float(i) / float(nu);
          p[v] += size[v] * float(j) / float(nv);
          points.push_back(p);
        }
      }
    }
  }
  return points;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "demo_scene_publisher");
  ros::NodeHandle nh, pnh("~");
  const std::string world = pnh.param<std::string>("world_frame", "world");
  const std::string root = pnh.param<std::string>("root_link", "base_link");
  const std::string camera = pnh.param<std::string>("camera_frame", "camera");
  const std::vector<double> camera_position = vector_param(pnh, "camera_position", {1.2, 0.0, 1.0});
  const std::vector<double> centre = vector_param(pnh, "pillar_center", {0.45, 0.35, 0.4});
  const std::vector<double> size = vector_param(pnh, "pillar_size", {0.12, 0.12, 0.8});
  std::vector<std::string> joint_names;
  pnh.getParam("joint_names", joint_names);
  const std::vector<double> positions = vector_param(pnh, "positions", std::vector<double>(joint_names.size(), 0.0));
  const double cloud_rate = pnh.param("cloud_rate", 2.0);
  if (positions.size() != joint_names.size() || camera_position.size() != 3 || centre.size() != 3 ||
      size.size() != 3 || cloud_rate <= 0.0) {
    ROS_FATAL("demo_scene_publisher: ~positions must match ~joint_names; positions and sizes are [x, y, z]");
    return 1;
  }

  tf2_ros::StaticTransformBroadcaster static_tf;
  static_tf.sendTransform({translation(world, root, {0.0, 0.0, 0.0}), translation(world, camera, camera_position)});

  // The pillar in the camera's frame (the camera is only translated).
  const Eigen::Vector3f offset{float(camera_position[0]), float(camera_position[1]), float(camera_position[2])};
  std::vector<ScanPoint> points =
      box_surface(Eigen::Vector3f(float(centre[0]), float(centre[1]), float(centre[2])),
                  Eigen::Vector3f(float(size[0]), float(size[1]), float(size[2])), 0.01f);
  for (ScanPoint& p : points) p -= offset;
  sensor_msgs::PointCloud2 cloud = bvh_collision::to_cloud_msg(points, camera);

  ros::Publisher joints_pub = nh.advertise<sensor_msgs::JointState>("joint_states", 10);
  ros::Publisher cloud_pub = nh.advertise<sensor_msgs::PointCloud2>("obstacle_cloud", 1);
  sensor_msgs::JointState state;
  state.name = joint_names;
  state.position = positions;
  ros::Rate rate(10.0);
  ros::Time next_cloud = ros::Time::now();
  while (ros::ok()) {
    state.header.stamp = ros::Time::now();
    joints_pub.publish(state);
    if (state.header.stamp >= next_cloud) {
      cloud.header.stamp = state.header.stamp;
      cloud_pub.publish(cloud);
      next_cloud = state.header.stamp + ros::Duration(1.0 / cloud_rate);
    }
    ros::spinOnce();
    rate.sleep();
  }
  return 0;
}
