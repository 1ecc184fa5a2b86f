// Launch test (issue 19, point 7): faults a deployed node meets. Joint states that stop: a query
// that needs joint values from joint_states (joints it leaves out, cast_ray) answers an error
// saying so once the last one is older than ~joint_state_timeout (0.5 s here); a query that
// gives every joint is still answered; when joint_states come back, so do the answers.
#include <atomic>
#include <thread>

#include <sensor_msgs/JointState.h>

#include "bvh_collision/CastRay.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

TEST(NodeFaults, JointStatesThatStop) {
  std::string urdf;
  ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
  const CollisionChecker checker = library_checker(urdf);
  ASSERT_TRUE(wait_for_node());
  ros::NodeHandle nh;
  ros::Publisher joints = nh.advertise<sensor_msgs::JointState>("joint_states", 10);
  const std::vector<double> upright(checker.model().variable_count(), 0.0);
  const auto publish_for = [&](double seconds) {
    for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds); ros::WallTime::now() < end;) {
      sensor_msgs::JointState js = joint_state(checker.model().variable_names(), upright);
      js.header.stamp = ros::Time::now();
      joints.publish(js);
      ros::WallDuration(0.02).sleep();
    }
  };
  CheckState::Request partial;  // joint2 only: the rest from joint_states
  partial.state = joint_state({"joint2"}, {0.3});
  const CheckState::Request full = state_request(checker, upright);
  CastRay::Request ray;
  ray.origin.x = 1.0;
  ray.origin.z = 0.5;
  ray.direction.x = -1.0;

  publish_for(1.0);  // connections, then a steady stream
  EXPECT_EQ(call<CheckState>("check_state", partial).response.error, "");
  EXPECT_EQ(call<CastRay>("cast_ray", ray).response.error, "");

  ros::WallDuration(1.0).sleep();  // the stream stops: older than the 0.5 s timeout
  const std::string error = call<CheckState>("check_state", partial).response.error;
  EXPECT_NE(error.find("joint_states"), std::string::npos) << error;
  EXPECT_NE(error.find("~joint_state_timeout"), std::string::npos) << error;
  EXPECT_NE(call<CastRay>("cast_ray", ray).response.error.find("~joint_state_timeout"), std::string::npos);
  const auto answered = call<CheckState>("check_state", full).response;
  EXPECT_EQ(answered.error, "") << "a request with every joint needs no joint_states";
  EXPECT_TRUE(answered.valid);

  publish_for(0.3);  // back
  EXPECT_EQ(call<CheckState>("check_state", partial).response.error, "");
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_faults"); }
