// Launch test: the node comes up on the demo robot, publishes its summary as one dictionary
// (~robot) before any service and ~ready once every service is served, stays up, and advertises
// every service it implements.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>

#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

const char* const kServices[] = {"check_state", "check_states", "check_motion", "check_motions", "cast_ray", "clear_environment",
                                 "clear_box", "set_collision_object", "remove_collision_object", "save_octree",
                                 "load_scene", "save_scene", "set_allowed_collisions", "attach_object", "detach_object"};

bool node_is_registered(const std::string& name) {
  std::vector<std::string> nodes;
  if (!ros::master::getNodes(nodes)) return false;
  return std::find(nodes.begin(), nodes.end(), name) != nodes.end();
}

std::string string_param(const std::string& name) {
  std::string value;
  EXPECT_TRUE(ros::param::get(name, value)) << name;
  return value;
}

// The summary, read in one call: every key there, of its type.
void expect_demo_summary(const std::string& node) {
  XmlRpc::XmlRpcValue robot;
  ASSERT_TRUE(ros::param::get(node + "/robot", robot)) << node << "/robot";
  ASSERT_EQ(robot.getType(), XmlRpc::XmlRpcValue::TypeStruct);
  EXPECT_EQ(static_cast<std::string>(robot["name"]), "demo_arm");
  EXPECT_EQ(static_cast<std::string>(robot["root_link"]), "base_link");
  EXPECT_EQ(static_cast<int>(robot["links"]), 11);
  EXPECT_EQ(static_cast<int>(robot["joints"]), 10);
  EXPECT_EQ(static_cast<int>(robot["collision_elements"]), 11);
  EXPECT_EQ(robot["variables"].size(), 7);
  EXPECT_GT(static_cast<int>(robot["checked_pairs"]), 0);
  EXPECT_GT(static_cast<double>(robot["reach"]), 0.0);
  EXPECT_EQ(robot["solid_links"].size(), 10);
  EXPECT_EQ(robot["open_meshes"].getType(), XmlRpc::XmlRpcValue::TypeArray);
}

// Whoever sees a service sees the whole summary: it is set, in one call, before the first
// service is advertised (set key by key after them, a reader in between saw half of it).
TEST(NodeStartup, SummaryComesBeforeAnyService) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (!ros::service::exists("/collision_checker/check_state", false)) {
    ASSERT_LT(ros::WallTime::now(), deadline) << "the node never advertised check_state";
    ros::WallDuration(0.005).sleep();
  }
  expect_demo_summary("/collision_checker");
}

TEST(NodeStartup, PublishesTheDemoRobotSummary) {
  ASSERT_TRUE(wait_for_node()) << "node never became ready";
  expect_demo_summary("/collision_checker");
  // world_frame defaults to the URDF root link.
  EXPECT_EQ(string_param("/collision_checker/world_frame"), "base_link");
  double resolution = 0.0;
  EXPECT_TRUE(ros::param::get("/collision_checker/resolution", resolution));
  EXPECT_EQ(resolution, 0.05);
}

TEST(NodeStartup, TakesTheWorldFrameArgument) {
  ASSERT_TRUE(wait_for_node("/framed/collision_checker"));
  EXPECT_EQ(string_param("/framed/collision_checker/world_frame"), "map");
}

TEST(NodeStartup, KeepsRunning) {
  ASSERT_TRUE(wait_for_node());
  ASSERT_TRUE(wait_for_node("/framed/collision_checker"));
  ros::WallDuration(2.0).sleep();
  EXPECT_TRUE(node_is_registered("/collision_checker"));
  EXPECT_TRUE(node_is_registered("/framed/collision_checker"));
}

// Ready means served: every service is there, and a call is answered.
TEST(NodeStartup, ReadyMeansEveryServiceIsServed) {
  ASSERT_TRUE(wait_for_node());
  for (const char* service : kServices) {
    EXPECT_TRUE(ros::service::exists(std::string("/collision_checker/") + service, false)) << service << " is not advertised";
  }
  EXPECT_EQ(call<CheckState>("check_state", CheckState::Request()).response.error, "");
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_startup");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
