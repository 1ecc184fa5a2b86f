// Launch test: a node given a missing, malformed or unusable robot description (or a bad
// parameter) exits non-zero at start-up with a message that says what is wrong.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <array>
#include <cstdio>
#include <sys/wait.h>

namespace {

struct RunResult {
  int exit_code = -1;  // 124: killed by the timeout, i.e. the node kept running
  std::string output;
};

// Starts the node as a user would (rosrun) in namespace `ns`, with a timeout.
RunResult run_node_in(const std::string& ns) {
  const std::string cmd = "timeout 30 rosrun bvh_collision collision_checker __ns:=/" + ns + " 2>&1";
  RunResult r;
  FILE* pipe = popen(cmd.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 512> buf{};
  while (fgets(buf.data(), buf.size(), pipe) != nullptr) r.output += buf.data();
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return r;
}

void expect_startup_failure(const std::string& ns, const std::string& reason) {
  const RunResult r = run_node_in(ns);
  EXPECT_NE(r.exit_code, 0) << "node exited 0 in /" << ns << ":\n" << r.output;
  EXPECT_NE(r.exit_code, 124) << "node kept running in /" << ns << ":\n" << r.output;
  EXPECT_LT(r.exit_code, 128) << "node crashed (signal) in /" << ns << ":\n" << r.output;
  EXPECT_NE(r.output.find(reason), std::string::npos)
      << "message for /" << ns << " does not say '" << reason << "':\n" << r.output;
}

TEST(NodeBadRobot, MissingDescription) {
  expect_startup_failure("nothing_here", "robot_description' is not set");
}

TEST(NodeBadRobot, EmptyDescription) { expect_startup_failure("empty", "robot description is empty"); }

TEST(NodeBadRobot, MalformedXml) { expect_startup_failure("malformed", "not well-formed XML"); }

TEST(NodeBadRobot, NotAUrdf) { expect_startup_failure("not_urdf", "no <robot> root element"); }

TEST(NodeBadRobot, DanglingJoint) { expect_startup_failure("dangling_joint", "ghost"); }

// Robot descriptions the node used to start with (an element dropped, a crash in the builder):
// the same message as bvh_collision_check gives.
TEST(NodeBadRobot, NonFiniteCylinderRadius) {
  expect_startup_failure("nan_radius", "link 'a', collision element 1: <cylinder> attribute 'radius' is 'nan': not finite");
}

TEST(NodeBadRobot, UnknownShape) {
  expect_startup_failure("capsule_shape", "unknown shape <capsule> (supported: box, sphere, cylinder, mesh)");
}

TEST(NodeBadRobot, NonFiniteMeshVertex) {
  expect_startup_failure("nan_vertex", "'nan' is not a finite number");
}

TEST(NodeBadRobot, NegativeResolution) {
  expect_startup_failure("bad_resolution", "~resolution must be a positive number");
}

TEST(NodeBadRobot, UnreadableOctreeFile) {
  expect_startup_failure("bad_octree", "cannot open octree file '/nonexistent/start.bt'");
}

TEST(NodeBadRobot, MalformedSceneFile) {
  expect_startup_failure("bad_scene", "/test/data/malformed.scene:7: object 'thing' shape 1 (sphere) radius is not a positive number");
  expect_startup_failure("bad_scene", "parameter ~scene_file: ");
}

TEST(NodeBadRobot, SensorModelHitBelowHalf) { expect_startup_failure("bad_sensor_model", "hit must be above 0.5"); }

TEST(NodeBadRobot, WorkspaceWithOneCorner) {
  expect_startup_failure("bad_workspace", "~workspace_min and ~workspace_max must be set together");
}

TEST(NodeBadRobot, PaddingForAnUnknownLink) {
  expect_startup_failure("bad_padding", "~link_padding names unknown link 'elbow'");
}

TEST(NodeBadRobot, ProxyLevelBelowAMillimetre) {
  expect_startup_failure("bad_proxy_levels", "~proxy_levels: every level must lie in [0.001, 1] m, got 0.000100");
}

// Limits (issue 19): each refused at start-up, naming the parameter that raises it.
TEST(NodeBadRobot, ServiceThreadsOutOfRange) {
  expect_startup_failure("huge_threads", "~service_threads must be a whole number from 1 to 64");
}

// A negative nice value would raise the cloud thread above the queries (and needs privilege).
TEST(NodeBadRobot, CloudNiceOutOfRange) {
  expect_startup_failure("negative_nice", "~cloud_nice must be a whole number from 0 to 19");
}

TEST(NodeBadRobot, RaysCrossingTooManyVoxels) {
  expect_startup_failure("long_rays", "~max_ray_voxels");  // 5 m at 0.1 mm: 50,000 voxels a ray
}

TEST(NodeBadRobot, MoreLinksThanTheLimit) { expect_startup_failure("many_links", "~max_robot_links"); }

TEST(NodeBadRobot, MoreCheckedPairsThanTheLimit) { expect_startup_failure("many_pairs", "~max_checked_pairs"); }

TEST(NodeBadRobot, ProxyLevelsNotAList) {
  expect_startup_failure("proxy_levels_not_list", "~proxy_levels must be a list of numbers (m)");
}

}  // namespace

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_bad_robot");
  ros::NodeHandle nh;
  return RUN_ALL_TESTS();
}
