// The fixture of the node's environment launch test (test_node_environment.cpp and
// test_node_environment_objects.cpp, one binary): the robot's base broadcast through tf as a
// localisation would, a static camera, the checker the test computes answers with, and a wall of
// points in the camera's frame.
#pragma once

#include <gtest/gtest.h>

#include <mutex>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include "bvh_collision/CastRay.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"

namespace bvh_collision::test {

inline const Vec3 kCamera(1.5, -0.5, 0.8);  // the camera's origin in world (translation only)

inline geometry_msgs::TransformStamped translation(const std::string& parent, const std::string& child, const Vec3& t) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = ros::Time::now();
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = t.x();
  m.transform.translation.y = t.y();
  m.transform.translation.z = t.z();
  m.transform.rotation.w = 1.0;
  return m;
}

// The robot's base in world, broadcast at 50 Hz as a localisation would.
class BaseBroadcaster {
 public:
  BaseBroadcaster() : timer_(nh_.createWallTimer(ros::WallDuration(0.02), &BaseBroadcaster::tick, this)) {}
  void move_to(const Vec3& t) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      base_ = t;
    }
  }

 private:
  void tick(const ros::WallTimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    tf_.sendTransform(translation("world", "base_link", base_));
  }
  ros::NodeHandle nh_;
  tf2_ros::TransformBroadcaster tf_;
  std::mutex mutex_;
  Vec3 base_ = Vec3::Zero();
  ros::WallTimer timer_;
};

class NodeEnvironment : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    base_ = new BaseBroadcaster();
    camera_tf_ = new tf2_ros::StaticTransformBroadcaster();
    camera_tf_->sendTransform(translation("world", "camera", kCamera));
    std::string urdf;
    ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
    checker_ = new CollisionChecker(library_checker(urdf));
    ASSERT_TRUE(wait_for_node());
    // Before any test clears it: the node started with ~scene_file's box at (0, 1.2, 0.3).
    CastRay::Request ray;
    ray.origin.y = 2.0, ray.origin.z = 0.3;
    ray.direction.y = -1.0;
    // (Once the base's transform has reached the node: a deadline for that event.)
    for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0); ros::WallTime::now() < end;) {
      start_scene_hit_ = call<CastRay>("cast_ray", ray).response;
      if (start_scene_hit_.error.empty()) break;
      ros::WallDuration(0.05).sleep();
    }
  }
  void SetUp() override {
    std_srvs::Empty empty;
    ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
    base_->move_to(Vec3::Zero());
  }
  const CollisionChecker& checker() const { return *checker_; }
  std::vector<double> arm(double j1, double j2) const {
    std::vector<double> q(checker().model().variable_count(), 0.0);
    q[0] = j1;
    q[1] = j2;
    return q;
  }
  CheckState::Response check(const std::vector<double>& q, std::uint32_t max_contacts = 0) const {
    CheckState::Request r = state_request(checker(), q);
    r.max_contacts = max_contacts;
    return call<CheckState>("check_state", r).response;
  }

  inline static BaseBroadcaster* base_ = nullptr;
  inline static CastRay::Response start_scene_hit_;
  inline static tf2_ros::StaticTransformBroadcaster* camera_tf_ = nullptr;
  inline static CollisionChecker* checker_ = nullptr;
};

// A wall of points 1 cm apart at x = 0.55 (world), y in [-0.25, 0.25], z in [0.3, 1.0], expressed
// in the camera's frame.
inline sensor_msgs::PointCloud2 wall_cloud() {
  std::vector<ScanPoint> points;
  for (double y = -0.25; y <= 0.25; y += 0.01) {
    for (double z = 0.3; z <= 1.0; z += 0.01) points.push_back((Vec3(0.55, y, z) - kCamera).cast<float>());
  }
  return to_cloud_msg(points, "camera");
}

template <class Predicate>
bool eventually(Predicate p, double seconds = 60.0) {  // a deadline for an event, not a speed
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds); ros::WallTime::now() < end;) {
    if (p()) return true;
    ros::WallDuration(0.05).sleep();
  }
  return p();
}

// A post at (0.6, 0, 0.5): a cone (height 0.4, base radius 0.1: radius 0.05 at mid height) over a
// box plinth below it.
inline SetCollisionObject::Request cone_on_plinth() {
  using shape_msgs::SolidPrimitive;
  SetCollisionObject::Request object;
  object.id = "post";
  object.pose = pose_at(Vec3(0.6, 0.0, 0.5));
  object.primitives = {solid(SolidPrimitive::CONE, {0.4, 0.1}), solid(SolidPrimitive::BOX, {0.3, 0.3, 0.1})};
  object.primitive_poses = {pose_at(Vec3::Zero()), pose_at(Vec3(0.0, 0.0, -0.25))};
  return object;
}

}  // namespace bvh_collision::test
