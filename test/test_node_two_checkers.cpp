// Two checkers on one cloud topic (launch/checker_pair.launch, namespaces checker_a and
// checker_b): after the same clouds, their octrees are the same file byte for byte, and the same
// queries get the same answers (states with distances, a batch, certified motions, rays), exactly.
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <random>

#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "bvh_collision/CastRay.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/CheckStates.h"
#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

const std::string kA = "/checker_a/collision_checker", kB = "/checker_b/collision_checker";
const Vec3 kCamera(1.2, 0.0, 1.0);

geometry_msgs::TransformStamped translation(const std::string& parent, const std::string& child, const Vec3& t) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = ros::Time::now();
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = t.x(), m.transform.translation.y = t.y(), m.transform.translation.z = t.z();
  m.transform.rotation.w = 1.0;
  return m;
}

// The demo's pillar (0.12 x 0.12 x 0.8 m at (0.45, 0.35, 0.4)) as the camera sees its faces, every 1 cm.
std::vector<ScanPoint> pillar_cloud() {
  std::vector<ScanPoint> points;
  for (const Vec3& p : box_surface(Transform::Translation(Vec3(0.45, 0.35, 0.4)), Vec3(0.12, 0.12, 0.8))) {
    points.push_back((p - kCamera).cast<float>());
  }
  return points;
}

std::string file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

TEST(TwoCheckers, SameCloudsSameOctreeSameAnswers) {
  ros::NodeHandle nh, pnh("~");
  ASSERT_TRUE(wait_for_node(kA));
  ASSERT_TRUE(wait_for_node(kB));
  const CollisionChecker checker = library_checker(pnh.param<std::string>("urdf_file", ""));
  const RobotModel& model = checker.model();

  tf2_ros::StaticTransformBroadcaster tf;
  tf.sendTransform({translation("world", "base_link", Vec3::Zero()), translation("world", "camera", kCamera)});
  const std::vector<double> upright(model.variable_count(), 0.0);
  ros::Publisher joints = nh.advertise<sensor_msgs::JointState>("/joint_states", 10);
  ros::WallTimer joint_timer = nh.createWallTimer(ros::WallDuration(0.05), [&](const ros::WallTimerEvent&) {
    joints.publish(joint_state(model.variable_names(), upright));
  });
  ros::Publisher clouds = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 3);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (clouds.getNumSubscribers() < 2 && ros::WallTime::now() < deadline) ros::WallDuration(0.05).sleep();
  ASSERT_EQ(clouds.getNumSubscribers(), 2u);
  const std::vector<ScanPoint> points = pillar_cloud();
  constexpr int kClouds = 3;
  // Unstamped clouds (the robot stands still: its current state and pose are those at any stamp).
  // Each is sent once both nodes have the one before: none supersedes a waiting one.
  for (int i = 0; i < kClouds; ++i) {
    sensor_msgs::PointCloud2 cloud = to_cloud_msg(points, "camera");
    clouds.publish(cloud);
    for (const std::string& node : {kA, kB}) wait_for_clouds(i + 1, 60.0, node);
  }
  for (const std::string& node : {kA, kB}) {
    const CloudCounts c = cloud_counts(node);
    EXPECT_EQ(c.inserted, static_cast<std::uint64_t>(kClouds)) << node;
    EXPECT_EQ(c.superseded, 0u) << node;
  }

  // The octrees, saved by each node.
  SaveOctree::Request save;
  save.path = "/tmp/bvh_collision_checker_a.bt";
  ASSERT_EQ(call_on<SaveOctree>(kA, "save_octree", save).response.error, "");
  save.path = "/tmp/bvh_collision_checker_b.bt";
  ASSERT_EQ(call_on<SaveOctree>(kB, "save_octree", save).response.error, "");
  const std::string a_tree = file_bytes("/tmp/bvh_collision_checker_a.bt"), b_tree = file_bytes("/tmp/bvh_collision_checker_b.bt");
  EXPECT_GT(a_tree.size(), 1000u) << "the pillar is in the octree";
  EXPECT_TRUE(a_tree == b_tree) << "the two octrees differ";

  // The same states, one by one and as a batch: the same answers, distances to the last bit.
  std::mt19937_64 rng(11);
  CheckStates::Request batch;
  batch.joint_names = model.variable_names();
  batch.checks = CheckStates::Request::SELF | CheckStates::Request::ENVIRONMENT;
  int environment_hits = 0;
  for (int i = 0; i < 100; ++i) {
    const std::vector<double> q = random_configuration(model, rng);
    batch.positions.insert(batch.positions.end(), q.begin(), q.end());
    CheckState::Request r = state_request(checker, q, CheckState::Request::SELF | CheckState::Request::ENVIRONMENT);
    r.distance = true;
    const auto ra = call_on<CheckState>(kA, "check_state", r).response, rb = call_on<CheckState>(kB, "check_state", r).response;
    ASSERT_EQ(ra.error, "");
    EXPECT_EQ(ra.valid, rb.valid) << i;
    EXPECT_EQ(ra.self_collision, rb.self_collision) << i;
    EXPECT_EQ(ra.environment_collision, rb.environment_collision) << i;
    EXPECT_EQ(ra.min_distance, rb.min_distance) << i;
    EXPECT_EQ(ra.closest_pair, rb.closest_pair) << i;
    environment_hits += ra.environment_collision;
  }
  EXPECT_GT(environment_hits, 0) << "some states reach the pillar";
  const auto ba = call_on<CheckStates>(kA, "check_states", batch).response, bb = call_on<CheckStates>(kB, "check_states", batch).response;
  ASSERT_EQ(ba.error, "");
  EXPECT_EQ(ba.valid, bb.valid);

  // Certified motions and rays.
  for (int i = 0; i < 5; ++i) {
    CheckMotion::Request m;
    m.joint_names = model.variable_names();
    m.start = random_configuration(model, rng);
    m.goal = random_configuration(model, rng);
    m.checks = CheckMotion::Request::SELF | CheckMotion::Request::ENVIRONMENT;
    const auto ma = call_on<CheckMotion>(kA, "check_motion", m).response, mb = call_on<CheckMotion>(kB, "check_motion", m).response;
    ASSERT_EQ(ma.error, "");
    EXPECT_EQ(ma.valid, mb.valid) << i;
    EXPECT_EQ(ma.last_valid_fraction, mb.last_valid_fraction) << i;
    EXPECT_EQ(ma.states_checked, mb.states_checked) << i;
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 20; ++i) {
    CastRay::Request ray;
    ray.origin.x = 1.0, ray.origin.z = 0.4 + 0.3 * u(rng);
    ray.direction.x = -1.0, ray.direction.y = 0.6 + 0.3 * u(rng), ray.direction.z = 0.2 * u(rng);
    const auto ra = call_on<CastRay>(kA, "cast_ray", ray).response, rb = call_on<CastRay>(kB, "cast_ray", ray).response;
    ASSERT_EQ(ra.error, "");
    EXPECT_EQ(ra.hit, rb.hit) << i;
    EXPECT_EQ(ra.body, rb.body) << i;
    EXPECT_EQ(ra.distance, rb.distance) << i;
  }
  joint_timer.stop();
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_two_checkers"); }
