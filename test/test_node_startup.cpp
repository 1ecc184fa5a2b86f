// Launch test: the node comes up on the demo robot, publishes its summary as parameters, stays
// up, and advertises no service it does not implement yet.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>

namespace {

// Waits until `param` exists (the node sets it once loaded); false after `timeout`.
bool wait_for_param(const std::string& param, double timeout) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::WallTime::now() < end) {
    if (ros::param::has(param)) return true;
    ros::WallDuration(0.05).sleep();
  }
  return false;
}

bool node_is_registered(const std::string& name) {
  std::vector<std::string> nodes;
  if (!ros::master::getNodes(nodes)) return false;
  return std::find(nodes.begin(), nodes.end(), name) != nodes.end();
}

int int_param(const std::string& name) {
  int value = -1;
  EXPECT_TRUE(ros::param::get(name, value)) << name;
  return value;
}

std::string string_param(const std::string& name) {
  std::string value;
  EXPECT_TRUE(ros::param::get(name, value)) << name;
  return value;
}

TEST(NodeStartup, PublishesTheDemoRobotSummary) {
  ASSERT_TRUE(wait_for_param("/collision_checker/robot/links", 30.0)) << "node never came up";
  EXPECT_EQ(string_param("/collision_checker/robot/name"), "demo_arm");
  EXPECT_EQ(string_param("/collision_checker/robot/root_link"), "base_link");
  EXPECT_EQ(int_param("/collision_checker/robot/links"), 11);
  EXPECT_EQ(int_param("/collision_checker/robot/joints"), 10);
  EXPECT_EQ(int_param("/collision_checker/robot/collision_elements"), 11);
  // world_frame defaults to the URDF root link.
  EXPECT_EQ(string_param("/collision_checker/world_frame"), "base_link");
}

TEST(NodeStartup, TakesTheWorldFrameArgument) {
  ASSERT_TRUE(wait_for_param("/framed/collision_checker/robot/links", 30.0));
  EXPECT_EQ(string_param("/framed/collision_checker/world_frame"), "map");
}

TEST(NodeStartup, KeepsRunning) {
  ASSERT_TRUE(wait_for_param("/collision_checker/robot/links", 30.0));
  ros::WallDuration(2.0).sleep();
  EXPECT_TRUE(node_is_registered("/collision_checker"));
  EXPECT_TRUE(node_is_registered("/framed/collision_checker"));
}

TEST(NodeStartup, AdvertisesEveryService) {
  ASSERT_TRUE(wait_for_param("/collision_checker/robot/links", 30.0));
  for (const char* service : {"check_state", "check_states", "check_motion", "cast_ray",
                              "clear_environment", "clear_box", "set_collision_object",
                              "remove_collision_object", "save_octree"}) {
    EXPECT_TRUE(ros::service::waitForService(std::string("/collision_checker/") + service, ros::Duration(10)))
        << service << " is not advertised";
  }
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_startup");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
