// Launch test: the node's environment through tf2, as a robot's drivers feed it. The node runs
// with world_frame "world"; this test is the robot's tf (world -> base_link, which it moves) and a
// camera (world -> camera, static) that publishes obstacle clouds in its own frame.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <std_srvs/Empty.h>

#include "bvh_collision/AttachObject.h"
#include "bvh_collision/CastRay.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/ClearBox.h"
#include "bvh_collision/DetachObject.h"
#include "bvh_collision/LoadScene.h"
#include "bvh_collision/RemoveCollisionObject.h"
#include "bvh_collision/SaveScene.h"
#include "bvh_collision/SetAllowedCollisions.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/ros/conversions.h"
#include "node_environment_fixture.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

TEST_F(NodeEnvironment, CloudInACameraFrameCollidesAndClearBoxFreesIt) {
  const auto reach = arm(0.0, 1.0), home = arm(0.0, 0.0);
  // The first test after start-up: the node may still lack the base's tf for a moment (a CI run
  // answered invalid here once); what it says then is printed.
  CheckState::Response first;
  ASSERT_TRUE(eventually([&] { return (first = check(reach)).valid; }))
      << "nothing to hit yet, but: error '" << first.error << "', self " << first.self_collision << ", environment "
      << first.environment_collision;
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1, true);
  sensor_msgs::PointCloud2 cloud = wall_cloud();
  cloud.header.stamp = ros::Time::now();
  pub.publish(cloud);
  ASSERT_TRUE(eventually([&] { return !check(reach).valid; })) << "the cloud never made the reach collide";
  const CheckState::Response hit = check(reach, 5);
  EXPECT_TRUE(hit.environment_collision);
  EXPECT_FALSE(hit.self_collision);
  ASSERT_FALSE(hit.contacts.empty());
  for (const Contact& c : hit.contacts) {
    EXPECT_EQ(c.body_b, "octree");
    // Contacts are in world: at the wall, not where the wall is in the camera's frame.
    EXPECT_NEAR(c.position.x, 0.55, 0.1) << c.body_a;
  }
  EXPECT_TRUE(check(home).valid) << "the arm upright stays clear of the wall";

  ClearBox::Request box;
  box.min.x = 0.5, box.min.y = -0.3, box.min.z = 0.25;
  box.max.x = 0.6, box.max.y = 0.3, box.max.z = 1.05;
  EXPECT_EQ(call<ClearBox>("clear_box", box).response.error, "");
  EXPECT_TRUE(check(reach).valid) << "clear_box left the wall in place";
}

TEST_F(NodeEnvironment, MarkersAndDiagnosticsShowTheCloud) {
  ros::NodeHandle nh;
  std::mutex mutex;
  visualization_msgs::MarkerArray cells;
  std::map<std::string, std::string> values;
  ros::Subscriber cells_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "/collision_checker/occupied_cells", 1, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        cells = *m;
      });
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& status : m->status) {
          for (const auto& kv : status.values) values[kv.key] = kv.value;
        }
      });
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1, true);
  sensor_msgs::PointCloud2 cloud = wall_cloud();
  cloud.header.stamp = ros::Time::now();
  pub.publish(cloud);
  ASSERT_TRUE(eventually([&] { return !check(arm(0.0, 1.0)).valid; }));
  const auto cube_count = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    std::size_t n = 0;
    for (const auto& m : cells.markers) {
      if (m.type == visualization_msgs::Marker::CUBE_LIST) n += m.points.size();
    }
    return n;
  };
  EXPECT_TRUE(eventually([&] { return cube_count() > 100; })) << cube_count() << " voxels drawn";
  const auto value = [&](const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex);
    return values.count(key) ? std::stoll(values[key]) : -1LL;
  };
  EXPECT_TRUE(eventually([&] { return value("clouds inserted") >= 1; }));
  EXPECT_GE(value("clouds received"), 1);
  EXPECT_GT(value("points received"), 3000);
  // (Diagnostics come once a period: the message that first counts this test's cloud may be older
  // than the map the check above saw, and an earlier test's cloud may already be counted.)
  EXPECT_TRUE(eventually([&] { return value("octree nodes") > 100; })) << value("octree nodes");
  EXPECT_GT(value("octree memory (bytes)"), 0);
  EXPECT_TRUE(eventually([&] { return value("check_state requests") >= 1; }));
}

// rviz started after a colliding query still shows its contacts: the topic is latched and the
// node publishes contacts whether or not anyone listens at the time (rviz, started late, showed
// none).
TEST_F(NodeEnvironment, ContactsReachASubscriberThatComesLater) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1, true);
  sensor_msgs::PointCloud2 cloud = wall_cloud();
  cloud.header.stamp = ros::Time::now();
  pub.publish(cloud);
  ASSERT_TRUE(eventually([&] { return !check(arm(0.0, 1.0)).valid; }));
  ros::WallDuration(0.2).sleep();  // past the node's 10 Hz limit on contact markers
  const auto answer = check(arm(0.0, 1.0), 3);
  ASSERT_FALSE(answer.contacts.empty());
  std::mutex mutex;
  std::size_t spheres = 0;
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "/collision_checker/contacts", 1, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& marker : m->markers) {
          if (marker.type == visualization_msgs::Marker::SPHERE_LIST) spheres = marker.points.size();
        }
      });
  EXPECT_TRUE(eventually([&] {
    std::lock_guard<std::mutex> lock(mutex);
    return spheres == answer.contacts.size();
  })) << spheres << " contact spheres received, " << answer.contacts.size() << " contacts answered";
}

TEST_F(NodeEnvironment, TheBasePoseComesFromTf) {
  SetCollisionObject::Request object = box_object("crate", Vec3(0.3, 0.3, 0.3), Vec3(2.0, 0.0, 0.6));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  const auto home = arm(0.0, 0.0);
  EXPECT_TRUE(check(home).valid);
  base_->move_to(Vec3(2.0, 0.0, 0.0));  // the crate is now where the arm stands, once tf says so
  ASSERT_TRUE(eventually([&] { return !check(home).valid; })) << "the node never took the base's new pose";
  const CheckState::Response moved = check(home, 1);
  EXPECT_FALSE(moved.valid);
  ASSERT_EQ(moved.contacts.size(), 1u);
  EXPECT_EQ(moved.contacts[0].body_b, "crate");
  EXPECT_NEAR(moved.contacts[0].position.x, 2.0, 0.2) << "contact not in world_frame";
  base_->move_to(Vec3(0.0, 0.0, 0.0));
  EXPECT_TRUE(eventually([&] { return check(home).valid; }));
  // An object given in another frame is placed through tf: (-1.5, 0.5, -0.2) from the camera is
  // (0, 0, 0.6) in world, onto the arm.
  object.frame_id = "camera";
  object.pose.position.x = -1.5;
  object.pose.position.y = 0.5;
  object.pose.position.z = -0.2;
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  EXPECT_FALSE(check(home).valid) << "an object given in the camera frame was not moved into world";
  RemoveCollisionObject::Request remove;
  remove.id = "crate";
  EXPECT_EQ(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
  EXPECT_TRUE(check(home).valid);
}

TEST_F(NodeEnvironment, CertifiedMotionFindsAThinObstacleThatACoarseStepMisses) {
  // A 2 mm plate in the plane y = 0 that the arm, leaning forward, sweeps through when joint1
  // turns from -0.75 to 0.85 rad.
  const auto plate = box_object("plate", Vec3(0.6, 0.002, 0.7), Vec3(0.6, 0.0, 0.65));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", plate).response.error, "");
  CheckMotion::Request motion;
  motion.joint_names = {"joint1", "joint2"};
  motion.start = {-0.75, 1.0};
  motion.goal = {0.85, 1.0};
  ASSERT_TRUE(check(arm(-0.75, 1.0)).valid);
  ASSERT_TRUE(check(arm(0.85, 1.0)).valid);
  ASSERT_FALSE(check(arm(0.0, 1.0)).valid) << "the plate must block the middle of the motion";

  // The library on the same scene: the coarse step misses the plate, the certified check does not.
  Environment env(0.02);
  env.add_object("plate", ObjectShape::box(Vec3(0.6, 0.002, 0.7)), Transform::Translation(Vec3(0.6, 0.0, 0.65)));
  const auto start = arm(-0.75, 1.0), goal = arm(0.85, 1.0);
  MotionRequest coarse_lib;
  coarse_lib.resolution = 0.7;
  ASSERT_TRUE(checker().check_motion(start.data(), goal.data(), env, coarse_lib).valid)
      << "the test's premise: a 0.7 rad step steps over the plate";

  motion.resolution = 0.7;
  const auto coarse = call<CheckMotion>("check_motion", motion).response;
  EXPECT_EQ(coarse.error, "");
  EXPECT_TRUE(coarse.valid) << "same answer as the library at resolution 0.7";
  EXPECT_EQ(coarse.states_checked, 4u);

  motion.resolution = 0.0;
  const auto certified = call<CheckMotion>("check_motion", motion).response;
  EXPECT_EQ(certified.error, "");
  EXPECT_FALSE(certified.valid) << "the certified check missed the plate";
  EXPECT_GT(certified.last_valid_fraction, 0.2);
  EXPECT_LT(certified.last_valid_fraction, 0.5) << "the plate is at joint1 = 0, fraction 0.47";
  // The node certifies through a SceneChecker (query/scene_checker.h), which finds the first
  // collision to a thousandth of the motion; the library's general check_motion steps up to it.
  const MotionResult lib = checker().check_motion(start.data(), goal.data(), env, MotionRequest{});
  EXPECT_NEAR(certified.last_valid_fraction, lib.last_valid_fraction, 1e-3);
  EXPECT_LE(certified.last_valid_fraction, lib.colliding_fraction) << "free up to beyond a collision";
}

TEST_F(NodeEnvironment, CastRayHitsLinksObjectsAndVoxels) {
  CastRay::Request ray;
  ray.origin.x = 1.0;
  ray.origin.z = 0.5;
  ray.direction.x = -1.0;
  auto r = call<CastRay>("cast_ray", ray).response;
  EXPECT_EQ(r.error, "");
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body.rfind("link", 0), 0u) << "the upright arm is hit first, not " << r.body;
  EXPECT_NEAR(r.point.x, 0.05, 0.02);

  const auto ball = primitive_object("ball", solid(shape_msgs::SolidPrimitive::SPHERE, {0.1}), Vec3(0.6, 0.0, 0.5));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", ball).response.error, "");
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "ball");
  EXPECT_NEAR(r.distance, 0.3, 1e-6);
  ray.max_range = 0.2;
  EXPECT_FALSE(call<CastRay>("cast_ray", ray).response.hit) << "max_range ends the ray before the ball";
  RemoveCollisionObject::Request remove;
  remove.id = "ball";
  EXPECT_EQ(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
}

// shape_msgs as MoveIt's CollisionObject carries them: an object of several shapes, each at its
// own pose, its parts named id#k; a cone is exact (a ray meets its slanted side where the
// cone's radius puts it, not where a faceted cone would), and replacing or removing the object
// takes every part.
TEST_F(NodeEnvironment, ShapeMsgsObjectsWithExactConesAndSeveralShapes) {
  using shape_msgs::SolidPrimitive;
  SetCollisionObject::Request object = cone_on_plinth();
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  CastRay::Request ray;
  ray.origin.x = 1.0, ray.origin.y = 0.0, ray.origin.z = 0.5;
  ray.direction.x = -1.0;
  auto r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "post#0");
  EXPECT_NEAR(r.distance, 0.35, 1e-9) << "the cone's radius at mid height is exactly 0.05";
  ray.origin.z = 0.69;  // 1 cm below the tip: radius 0.0025
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.distance, 0.4 - 0.0025, 1e-9);
  ray.origin.z = 0.25;  // the plinth
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "post#1");
  EXPECT_NEAR(r.distance, 0.25, 1e-9);

  // Replaced by one shape: no part of the old object stays behind.
  object.primitives = {solid(SolidPrimitive::CYLINDER, {0.4, 0.02})};
  object.primitive_poses = {pose_at(Vec3::Zero())};
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  r = call<CastRay>("cast_ray", ray).response;
  EXPECT_TRUE(!r.hit || r.body.rfind("post", 0) != 0) << "the plinth was replaced, hit " << r.body;
  ray.origin.z = 0.5;
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "post");
  EXPECT_NEAR(r.distance, 0.38, 1e-9);

  // Two shapes again, then removed together by the object's id.
  object.primitives.push_back(solid(SolidPrimitive::SPHERE, {0.05}));
  object.primitive_poses.push_back(pose_at(Vec3(0.0, 0.0, -0.3)));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  RemoveCollisionObject::Request remove;
  remove.id = "post";
  EXPECT_EQ(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
  for (const double z : {0.5, 0.2}) {
    ray.origin.z = z;
    r = call<CastRay>("cast_ray", ray).response;
    EXPECT_TRUE(!r.hit || r.body.rfind("post", 0) != 0) << "removed, still hit " << r.body << " at z " << z;
  }
  EXPECT_NE(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_environment");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);  // tf broadcasts and subscriptions run while tests wait
  spinner.start();
  return RUN_ALL_TESTS();
}
