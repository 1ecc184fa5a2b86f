// JointStateHistory (robot/joint_state_history.h): the robot's joint values at a past moment,
// against the trajectory that produced the recorded states.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bvh_collision/robot/joint_state_history.h"
#include "bvh_collision/robot/robot_description.h"

namespace bvh_collision {
namespace {

constexpr const char* kUrdf = R"(<robot name="two">
  <link name="base"/><link name="a"/><link name="b"/>
  <joint name="swing" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="spin" type="continuous"><parent link="a"/><child link="b"/><axis xyz="1 0 0"/></joint>
</robot>)";

RobotModel two_joints() { return RobotModel::from_urdf(*parse_robot_description(kUrdf), PackageResolver({})); }

// States sampled every 10 ms from a motion at 1.5 rad/s: between samples the history gives the
// motion itself (it is linear), at a sample the sample.
TEST(JointStateHistory, InterpolatesTheMotionBetweenSamples) {
  const RobotModel model = two_joints();
  JointStateHistory history(model, 10.0, 0.05);
  const auto motion = [](double t) { return std::vector<double>{-1.0 + 1.5 * t, 0.5 - 0.7 * t}; };
  for (int k = 0; k <= 200; ++k) history.record(100.0 + 0.01 * k, motion(0.01 * k));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(0.0, 2.0);
  for (int i = 0; i < 1000; ++i) {
    const double t = u(rng);
    const auto q = history.at(100.0 + t);
    ASSERT_TRUE(q.has_value()) << t;
    EXPECT_NEAR((*q)[0], motion(t)[0], 1e-9);
    EXPECT_NEAR((*q)[1], motion(t)[1], 1e-9);
  }
  EXPECT_EQ(*history.at(100.5), motion(0.5));
}

// Before the oldest state and beyond the newest by more than the lead, the pose is unknown;
// within the lead it is the newest state.
TEST(JointStateHistory, OutsideTheHistoryThereIsNoAnswer) {
  const RobotModel model = two_joints();
  JointStateHistory history(model, 10.0, 0.05);
  EXPECT_FALSE(history.at(0.0).has_value());  // nothing recorded
  history.record(5.0, {0.1, 0.2});
  history.record(6.0, {0.3, 0.4});
  EXPECT_FALSE(history.at(4.999).has_value());
  EXPECT_EQ(*history.at(6.04), (std::vector<double>{0.3, 0.4}));
  EXPECT_FALSE(history.at(6.06).has_value());
  EXPECT_FALSE(history.at(std::nan("")).has_value());
}

// Only the horizon is kept; late states go in order; a repeated time replaces its state.
TEST(JointStateHistory, KeepsTheHorizonInTimeOrder) {
  const RobotModel model = two_joints();
  JointStateHistory history(model, 1.0, 0.0);
  for (int k = 0; k < 300; ++k) history.record(0.01 * k, {0.01 * k, 0.0});
  EXPECT_NEAR(history.newest(), 2.99, 1e-12);
  EXPECT_GE(history.oldest(), 1.99 - 1e-12);
  EXPECT_FALSE(history.at(1.5).has_value());
  history.record(2.505, {7.0, 0.0});  // late, out of order
  EXPECT_EQ((*history.at(2.505))[0], 7.0);
  EXPECT_NEAR((*history.at(2.5025))[0], 0.5 * (2.50 + 7.0), 1e-9);
  const std::size_t n = history.size();
  history.record(2.505, {8.0, 0.0});  // the same time: replaced
  EXPECT_EQ(history.size(), n);
  EXPECT_EQ((*history.at(2.505))[0], 8.0);
}

// A continuous joint crossing +-pi turns the short way (3.1 -> -3.1 is 0.083 rad, not 6.2).
TEST(JointStateHistory, ContinuousJointsTurnTheShortWay) {
  const RobotModel model = two_joints();
  JointStateHistory history(model, 10.0, 0.0);
  history.record(0.0, {2.9, 3.1});
  history.record(1.0, {-2.9, -3.1});
  const auto mid = *history.at(0.5);
  EXPECT_NEAR(mid[0], 0.0, 1e-12);  // a revolute joint goes straight
  EXPECT_NEAR(std::abs(std::remainder(mid[1], 2 * M_PI)), M_PI, 1e-9);
}

TEST(JointStateHistory, BadInputIsAnError) {
  const RobotModel model = two_joints();
  EXPECT_THROW(JointStateHistory(model, -1.0, 0.0), std::invalid_argument);
  EXPECT_THROW(JointStateHistory(model, 1.0, std::nan("")), std::invalid_argument);
  JointStateHistory history(model, 1.0, 0.0);
  EXPECT_THROW(history.record(0.0, {1.0}), std::invalid_argument);
  EXPECT_THROW(history.record(INFINITY, {1.0, 2.0}), std::invalid_argument);
  EXPECT_TRUE(history.empty());
}

}  // namespace
}  // namespace bvh_collision
