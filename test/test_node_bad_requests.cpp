// Launch test: every kind of bad input of docs/design.md gets an error that names what is
// wrong, changes nothing, and leaves the node serving: unknown joints, wrong array lengths, NaN
// and Inf, values outside joint limits (answered, with a warning), unknown frames, bad shapes,
// unwritable octree paths, malformed clouds and clouds whose transform never comes, a robot
// without collision geometry.
#include <gmock/gmock.h>

#include <chrono>
#include <filesystem>
#include <limits>
#include <mutex>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <sensor_msgs/PointField.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "bvh_collision/CastRay.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/CheckStates.h"
#include "bvh_collision/ClearBox.h"
#include "bvh_collision/RemoveCollisionObject.h"
#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

MATCHER_P(Says, text, "") { return arg.find(text) != std::string::npos; }

class NodeBadRequests : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    static tf2_ros::StaticTransformBroadcaster tf;
    geometry_msgs::TransformStamped base;
    base.header.frame_id = "world";
    base.child_frame_id = "base_link";
    base.transform.rotation.w = 1.0;
    tf.sendTransform(base);
    ASSERT_TRUE(wait_for_node());
    // Until the node has the transform, environment checks say that they cannot place the robot.
    std::string error = "no answer";
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
    while (!(error = call<CheckState>("check_state", CheckState::Request()).response.error).empty() &&
           ros::WallTime::now() < deadline) {
      ros::WallDuration(0.05).sleep();
    }
    ASSERT_EQ(error, "") << "the node never got world -> base_link";
  }
  // After every bad request: the node still answers, with the state it had.
  void TearDown() override {
    CheckState::Request r;
    r.state = joint_state({"joint2"}, {1.2});
    const auto res = call<CheckState>("check_state", r).response;
    EXPECT_EQ(res.error, "") << "the node stopped answering good requests";
    EXPECT_EQ(res.valid, !keeper_set_) << "a bad request changed the environment";
  }
  // An object the arm meets when leaning forward: bad requests must leave it in place.
  void set_keeper() {
    const auto object = box_object("keeper", Vec3(0.2, 0.4, 0.2), Vec3(0.6, 0.0, 0.5));
    ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
    keeper_set_ = true;
  }
  static bool keeper_set_;
};
bool NodeBadRequests::keeper_set_ = false;

CheckState::Request state(const std::vector<std::string>& names, const std::vector<double>& values) {
  CheckState::Request r;
  r.state = joint_state(names, values);
  return r;
}

TEST_F(NodeBadRequests, CheckStateNamesWhatIsWrong) {
  set_keeper();
  const auto error = [](const CheckState::Request& r) { return call<CheckState>("check_state", r).response.error; };
  EXPECT_THAT(error(state({"joint1", "elbow"}, {0.0, 0.0})), Says("unknown joint 'elbow'"));
  EXPECT_THAT(error(state({"joint1", "joint2"}, {0.0})), Says("2 joint names and 1 positions"));
  EXPECT_THAT(error(state({"joint1"}, {kNaN})), Says("'joint1' has value nan"));
  EXPECT_THAT(error(state({"joint1"}, {kInf})), Says("'joint1' has value inf"));
  EXPECT_THAT(error(state({"joint1", "joint1"}, {0.0, 0.1})), Says("named twice"));
  EXPECT_THAT(error(state({"hand_joint"}, {0.0})), Says("fixed"));
  CheckState::Request checks = state({}, {});
  checks.checks = 7;
  EXPECT_THAT(error(checks), Says("checks must be"));
  CheckState::Request tolerance = state({}, {});
  tolerance.tolerance = kNaN;
  EXPECT_THAT(error(tolerance), Says("tolerance"));
}

TEST_F(NodeBadRequests, ValuesOutsideLimitsAreAnsweredWithAWarning) {
  const auto res = call<CheckState>("check_state", state({"joint2"}, {2.5})).response;
  EXPECT_EQ(res.error, "");
  EXPECT_THAT(res.warning, Says("'joint2' = 2.5 is outside its limits [-2, 2]"));
  CheckStates::Request batch;
  batch.joint_names = {"joint2"};
  batch.positions = {0.0, 2.5};
  const auto b = call<CheckStates>("check_states", batch).response;
  EXPECT_EQ(b.error, "");
  EXPECT_EQ(b.valid.size(), 2u);
  EXPECT_THAT(b.warning, Says("configuration 1"));
}

TEST_F(NodeBadRequests, CheckStatesAndCheckMotion) {
  const auto batch_error = [](const std::vector<std::string>& names, const std::vector<double>& positions) {
    CheckStates::Request r;
    r.joint_names = names;
    r.positions = positions;
    const auto res = call<CheckStates>("check_states", r).response;
    EXPECT_TRUE(res.valid.empty()) << "no answers with an error";
    return res.error;
  };
  EXPECT_THAT(batch_error({"joint1", "joint2"}, {0, 0, 0}), Says("not a multiple of 2"));
  EXPECT_THAT(batch_error({"joint1"}, {0, 0, kNaN}), Says("configuration 2"));
  EXPECT_THAT(batch_error({"joint9"}, {0}), Says("unknown joint 'joint9'"));
  EXPECT_THAT(batch_error({}, {0.0}), Says("joint_names is empty"));
  // Limits (the .test file sets ~max_batch_states 500): named, with the parameter that raises them.
  EXPECT_THAT(batch_error({"joint1"}, std::vector<double>(501, 0.0)), Says("~max_batch_states"));
  EXPECT_TRUE(call<CheckStates>("check_states", [] {
                CheckStates::Request r;
                r.joint_names = {"joint1"};
                r.positions.assign(500, 0.0);
                return r;
              }()).response.error.empty())
      << "500 configurations are within the limit";

  const auto motion_error = [](std::vector<double> start, std::vector<double> goal, double resolution) {
    CheckMotion::Request r;
    r.joint_names = {"joint1"};
    r.start = start;
    r.goal = goal;
    r.resolution = resolution;
    return call<CheckMotion>("check_motion", r).response.error;
  };
  EXPECT_THAT(motion_error({0.0}, {0.0, 1.0}, 0.1), Says("goal 2 for 1 joint names"));
  EXPECT_THAT(motion_error({0.0}, {1.0}, -0.1), Says("resolution"));
  EXPECT_THAT(motion_error({0.0}, {1.0}, kNaN), Says("resolution"));
  EXPECT_THAT(motion_error({0.0}, {kInf}, 0.1), Says("'joint1' has value inf"));
  // 3 rad at 1e-9 rad once kept the node busy for ten minutes; 1e-300 made the count undefined.
  // Refused before any state is checked: the node's count of states checked does not move.
  const std::string checked = diagnostic("states checked");
  EXPECT_THAT(motion_error({-1.5}, {1.5}, 1e-9), Says("~max_motion_states"));
  EXPECT_THAT(motion_error({-1.5}, {1.5}, 1e-300), Says("~max_motion_states"));
  EXPECT_NE(checked, "(missing)");
  EXPECT_EQ(diagnostic("states checked"), checked);
}

TEST_F(NodeBadRequests, RaysAndBoxes) {
  CastRay::Request ray;
  ray.origin.z = 0.5;
  EXPECT_THAT(call<CastRay>("cast_ray", ray).response.error, Says("direction"));
  ray.direction.x = 1.0;
  ray.origin.x = kNaN;
  EXPECT_THAT(call<CastRay>("cast_ray", ray).response.error, Says("origin"));
  ClearBox::Request box;
  box.min.x = 1.0;
  EXPECT_THAT(call<ClearBox>("clear_box", box).response.error, Says("min exceeds max"));
  box.min.x = kNaN;
  EXPECT_THAT(call<ClearBox>("clear_box", box).response.error, Says("finite"));
}

TEST_F(NodeBadRequests, CollisionObjects) {
  set_keeper();
  SetCollisionObject::Request object;
  object.id = "bad";
  object.pose.orientation.w = 1.0;
  object.pose.position.z = 0.5;  // onto the arm: had any of these been added, the arm would collide
  const auto error = [&](auto edit) {
    SetCollisionObject::Request r = object;
    edit(r);
    return call<SetCollisionObject>("set_collision_object", r).response.error;
  };
  using shape_msgs::SolidPrimitive;
  auto one = [](auto& r, const SolidPrimitive& shape) { r.primitives = {shape}, r.primitive_poses = {pose_at(Vec3::Zero())}; };
  EXPECT_THAT(error([&](auto& r) { one(r, solid(9, {})); }), Says("primitives[0]: unknown solid primitive type 9"));
  EXPECT_THAT(error([&](auto& r) { one(r, solid(SolidPrimitive::BOX, {1, 1})); }), Says("BOX needs 3 dimensions"));
  EXPECT_THAT(error([&](auto& r) { one(r, solid(SolidPrimitive::SPHERE, {-1})); }), Says("positive and finite"));
  EXPECT_THAT(error([&](auto& r) { one(r, solid(SolidPrimitive::CONE, {0.2})); }), Says("CONE needs 2 dimensions (height, radius)"));
  EXPECT_THAT(error([&](auto& r) {
                r.mesh_resources = {"/no/such/mesh.stl"};
                r.mesh_resource_poses = {pose_at(Vec3::Zero())};
              }),
              Says("mesh_resources[0]: mesh '/no/such/mesh.stl'"));
  EXPECT_THAT(error([&](auto& r) {
                r.mesh_resources = {"/no/such/mesh.stl"};
                r.mesh_resource_poses = {pose_at(Vec3::Zero())};
                r.mesh_resource_scales.resize(2);
              }),
              Says("mesh_resource_scales holds 2 scales for 1 mesh resources"));
  EXPECT_THAT(error([&](auto& r) {
                r.meshes.resize(1);
                r.meshes[0].vertices.resize(2);
                r.meshes[0].triangles.resize(1);
                r.meshes[0].triangles[0].vertex_indices = {0, 1, 2};
                r.mesh_poses = {pose_at(Vec3::Zero())};
              }),
              Says("meshes[0]: triangle vertex index 2 is out of range"));
  EXPECT_THAT(error([&](auto& r) { r.primitives = {solid(SolidPrimitive::SPHERE, {0.1})}; }),
              Says("primitives: 1 shapes but 0 poses"));
  EXPECT_THAT(error([&](auto&) {}), Says("has no shape"));
  EXPECT_THAT(error([&](auto& r) {
                one(r, solid(SolidPrimitive::SPHERE, {0.1}));
                r.primitive_poses[0].orientation.w = 0.0;
              }),
              Says("primitives[0]: "));
  EXPECT_THAT(error([&](auto& r) {
                one(r, solid(SolidPrimitive::SPHERE, {0.1}));
                r.pose.orientation.w = 2.0;
              }),
              Says("unit quaternion"));
  EXPECT_THAT(error([&](auto& r) {
                one(r, solid(SolidPrimitive::SPHERE, {0.1}));
                r.frame_id = "nowhere";
              }),
              Says("unknown frame 'nowhere'"));
  EXPECT_THAT(error([&](auto& r) {
                one(r, solid(SolidPrimitive::SPHERE, {0.1}));
                r.id = "";
              }),
              Says("id is empty"));
  EXPECT_THAT(error([&](auto& r) {
                one(r, solid(SolidPrimitive::SPHERE, {0.1}));
                r.id = "table#1";
              }),
              Says("contains '#'"));
  EXPECT_THAT(error([&](auto& r) {  // 101 triangles in two meshes; the .test file sets ~max_object_triangles 100
                r.meshes.resize(2);
                for (int m = 0; m < 2; ++m) {
                  r.meshes[m].vertices.resize(3);
                  r.meshes[m].vertices[1].x = r.meshes[m].vertices[2].y = 0.1;
                  r.meshes[m].triangles.resize(m == 0 ? 50 : 51);
                  for (auto& t : r.meshes[m].triangles) t.vertex_indices = {0, 1, 2};
                }
                r.mesh_poses = {pose_at(Vec3::Zero()), pose_at(Vec3::Zero())};
              }),
              Says("~max_object_triangles"));
  RemoveCollisionObject::Request remove;
  remove.id = "ghost";
  EXPECT_THAT(call<RemoveCollisionObject>("remove_collision_object", remove).response.error,
              Says("no collision object with id 'ghost'"));
}

TEST_F(NodeBadRequests, SaveOctree) {
  SaveOctree::Request save;
  save.path = "/nonexistent_dir/octree.bt";
  EXPECT_THAT(call<SaveOctree>("save_octree", save).response.error, Says("cannot write"));
  save.path = "/tmp/octree.txt";
  EXPECT_THAT(call<SaveOctree>("save_octree", save).response.error, Says(".bt or .ot"));
  save.path = "";
  EXPECT_THAT(call<SaveOctree>("save_octree", save).response.error, Says("path is empty"));
  const std::string good = "/tmp/bvh_collision_test_" + std::to_string(getpid()) + ".ot";
  save.path = good;
  EXPECT_EQ(call<SaveOctree>("save_octree", save).response.error, "");
  EXPECT_TRUE(std::filesystem::exists(good));
  std::filesystem::remove(good);
}

// Each bad cloud is counted by its reason; each is sent once the one before has its outcome, so
// none is superseded however busy the machine (with the reasons, the counts are exact).
TEST_F(NodeBadRequests, BadCloudsAreCountedNotInserted) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 10);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (pub.getNumSubscribers() < 1) {
    ASSERT_LT(ros::WallTime::now(), deadline) << "the node never subscribed to /obstacle_cloud";
    ros::WallDuration(0.05).sleep();
  }
  std::vector<ScanPoint> wall;
  for (int i = 0; i < 100; ++i) wall.emplace_back(0.5f, 0.01f * i, 0.5f);
  std::vector<sensor_msgs::PointCloud2> bad(4, to_cloud_msg(wall, "world"));
  bad[0].fields.pop_back();                                         // no z
  bad[1].fields[0].datatype = sensor_msgs::PointField::INT32;       // x is not a float
  bad[2].data.resize(bad[2].data.size() / 2);                       // data shorter than promised
  bad[3].fields[2].offset = 10;                                     // z beyond point_step
  std::vector<ScanPoint> big(1001, ScanPoint(0.5f, 0.0f, 0.5f));
  bad.push_back(to_cloud_msg(big, "world"));                        // beyond ~max_cloud_points (1000)
  bad.push_back(to_cloud_msg(wall, "nowhere"));                     // no transform will come
  const std::uint64_t before = cloud_counts().sent();
  for (std::size_t i = 0; i < bad.size(); ++i) {
    bad[i].header.stamp = ros::Time::now();
    pub.publish(bad[i]);
    wait_for_clouds(before + i + 1);
  }
  const CloudCounts c = cloud_counts();
  EXPECT_EQ(c.malformed, 4u);
  EXPECT_EQ(c.over_limit, 1u);
  EXPECT_EQ(c.no_transform, 1u);
  EXPECT_EQ(c.inserted, 0u);
  EXPECT_EQ(c.superseded, 0u);
  EXPECT_EQ(c.received, 6u);
}

TEST_F(NodeBadRequests, ARobotWithoutGeometryIsAnError) {
  ASSERT_TRUE(wait_for_node("/empty_robot/collision_checker"));
  CheckState srv;
  ASSERT_TRUE(ros::service::call("/empty_robot/collision_checker/check_state", srv));
  EXPECT_THAT(srv.response.error, Says("has no collision geometry"));
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_bad_requests"); }
