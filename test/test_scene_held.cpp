// SceneChecker's held pairs (src/query/held_pair_clearance.h): a self pair that a motion moves by
// one joint of its path, the path's other joints held (a planning group beside a tucked arm), is
// proven clear along that joint once per thread and model. Motions answer as they do without the
// proofs, where the pair's clearance along the joint crosses its padding (the proofs must stop
// exactly there), and as conservative advancement with exact distances answers them (another
// algorithm); sweeps past the tucked gripper take a few intervals each, on the checker that
// proved the pair and on the next. One binary with test_scene_checker.cpp.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <string>

#include "bvh_collision/query/scene_checker.h"
#include "advancement_oracle.h"
#include "checker_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

// PR2 as MoveIt sets it up, the torso half raised and the left arm tucked beside the body as
// pr2's tuck_arms leaves it: its gripper a few millimetres from the right shoulder's pan link.
// (`padding` on every link: a self pair's clearance less twice it.)
struct TuckedPr2 {
  CollisionChecker checker;
  std::vector<double> tucked;
  std::vector<std::size_t> right_arm;  // the variables of the right arm's seven joints

  explicit TuckedPr2(double padding = 0.0) : checker(load(padding)), tucked(checker.model().variable_count(), 0.0) {
    const std::map<std::string, double> values = {
        {"torso_lift_joint", 0.15},      {"l_shoulder_pan_joint", 0.06}, {"l_shoulder_lift_joint", 1.25},
        {"l_upper_arm_roll_joint", 1.79}, {"l_elbow_flex_joint", -1.68},  {"l_forearm_roll_joint", -1.73},
        {"l_wrist_flex_joint", -0.1},     {"l_wrist_roll_joint", -0.09}};
    for (const auto& [joint, value] : values) tucked[variable(joint)] = value;
    for (const char* joint : {"r_shoulder_pan_joint", "r_shoulder_lift_joint", "r_upper_arm_roll_joint", "r_elbow_flex_joint",
                              "r_forearm_roll_joint", "r_wrist_flex_joint", "r_wrist_roll_joint"}) {
      right_arm.push_back(variable(joint));
    }
  }
  static CollisionChecker load(double padding) {
    CheckerOptions options;  // proxy levels as a planner's checker has them (the finest left out: its build)
    options.proxy_levels = {0.01, 0.02};
    options.proxy_cache = test::proxy_cache_dir();
    options.padding = padding;
    return test::load_as_moveit("pr2", options);
  }
  std::size_t variable(const std::string& joint) const {
    const RobotModel& model = checker.model();
    return static_cast<std::size_t>(model.joints()[model.joint_index(joint)].variable);
  }
  const RobotJoint& joint_of(std::size_t v) const {
    for (const RobotJoint& j : checker.model().joints()) {
      if (j.variable == static_cast<int>(v) && j.mimic < 0) return j;
    }
    throw std::logic_error("no joint");
  }
  // A value of variable v's joint across its range from `from` (its other half, drawn uniformly).
  double far_value(std::size_t v, double from, std::mt19937_64& rng) const {
    const RobotJoint& j = joint_of(v);
    const double lower = j.bounded ? j.lower : -M_PI, upper = j.bounded ? j.upper : M_PI, mid = 0.5 * (lower + upper);
    return from < mid ? std::uniform_real_distribution<double>(mid, upper)(rng) : std::uniform_real_distribution<double>(lower, mid)(rng);
  }
  // The tucked state with the right arm drawn uniformly within its limits (wrist roll's +-pi).
  std::vector<double> random_right_arm(std::mt19937_64& rng) const {
    std::vector<double> q = tucked;
    for (const std::size_t v : right_arm) {
      const RobotJoint& j = joint_of(v);
      const double lower = j.bounded ? j.lower : -M_PI, upper = j.bounded ? j.upper : M_PI;
      q[v] = std::uniform_real_distribution<double>(lower, upper)(rng);
    }
    return q;
  }
};

const TuckedPr2& pr2() {
  static const TuckedPr2 robot;
  return robot;
}

// Sweeps of the right shoulder's pan joint from and to free states, with every link padded by
// 2 mm: the tucked gripper's finger, 4.2-4.5 mm from the pan link over most of the joint's range
// and 3.5 mm over a tenth of it, then collides with it there and clears it by 0.2-0.5 mm
// elsewhere. The answers, with the proofs and without (each sweep on a new checker of the same
// model, the proofs kept), are the same; some sweeps are free, some collide.
TEST(SceneHeldPairs, SweepsWhereThePaddingCutsTheRangeAnswerAsWithoutTheProofs) {
  BVH_REQUIRE_ROBOTS();
  const TuckedPr2 robot(0.002);
  const auto empty = std::make_shared<const Environment>(0.05);
  SceneCheckOptions with, without;
  with.environment = without.environment = false;
  without.held_pairs = false;
  std::mt19937_64 rng(57);
  const std::size_t pan = robot.variable("r_shoulder_pan_joint");
  int motions = 0, free = 0;
  std::size_t intervals_with = 0, intervals_without = 0;
  for (int attempt = 0; attempt < 2000 && motions < test::sized(40); ++attempt) {
    const std::vector<double> a = robot.random_right_arm(rng);
    std::vector<double> b = a;
    b[pan] = robot.far_value(pan, a[pan], rng);
    if (robot.checker.check_self(a.data()).collision || robot.checker.check_self(b.data()).collision) continue;
    ++motions;
    const MotionResult proved = SceneChecker(robot.checker, empty, with).check_motion(a.data(), b.data());
    const MotionResult settled = SceneChecker(robot.checker, empty, without).check_motion(a.data(), b.data());
    ASSERT_TRUE(proved.certified && settled.certified) << proved.message << settled.message;
    ASSERT_EQ(proved.valid, settled.valid) << "sweep " << motions << " from " << a[pan] << " to " << b[pan];
    free += proved.valid;
    intervals_with += proved.states_checked;
    intervals_without += settled.states_checked;
  }
  std::cout << motions << " sweeps of the pan joint, 2 mm padding, " << free << " free: " << intervals_with
            << " intervals with the proofs, " << intervals_without << " without\n";
  EXPECT_GT(free, motions / 5);
  EXPECT_LT(free, motions - motions / 5);
  EXPECT_LT(intervals_with, intervals_without);
}

// Sweeps of the pan joint (past the tucked gripper) and of the arm's other joints across their
// ranges, unpadded, answer as conservative advancement does.
TEST(SceneHeldPairs, SweepsOfOneJointAnswerAsAdvancement) {
  BVH_REQUIRE_ROBOTS();
  const TuckedPr2& robot = pr2();
  const auto empty = std::make_shared<const Environment>(0.05);
  SceneCheckOptions options;
  options.environment = false;
  const SceneChecker scene(robot.checker, empty, options);
  std::mt19937_64 rng(57);
  int motions = 0, free = 0;
  const std::size_t pan = robot.variable("r_shoulder_pan_joint");
  for (int attempt = 0; attempt < 400 && motions < test::sized(6); ++attempt) {
    const std::vector<double> a = robot.random_right_arm(rng);
    std::vector<double> b = a;
    const std::size_t v = attempt % 2 == 0 ? pan : robot.right_arm[rng() % robot.right_arm.size()];
    b[v] = robot.far_value(v, a[v], rng);
    if (robot.checker.check_self(a.data()).collision || robot.checker.check_self(b.data()).collision) continue;
    ++motions;
    const MotionResult ours = scene.check_motion(a.data(), b.data());
    MotionRequest request;
    request.environment = false;
    const MotionResult truth = test::advancement_motion(robot.checker, a.data(), b.data(), *empty, request);
    ASSERT_TRUE(truth.certified) << truth.message;
    ASSERT_TRUE(ours.certified) << ours.message;
    EXPECT_EQ(ours.valid, truth.valid) << "motion " << motions << " of " << robot.checker.model().variable_names()[v];
    free += ours.valid;
  }
  std::cout << motions << " sweeps of one joint, " << free << " free\n";
  EXPECT_GT(free, 0);
}

// Sweeps of the pan joint past the tucked gripper (4 mm from the pan link): without the proofs
// each takes dozens of intervals; with them a few, on the checker that proved the pairs and on a
// new checker of the same model (a planner's next problem gets one).
TEST(SceneHeldPairs, SweepsPastATuckedGripperTakeAFewIntervals) {
  BVH_REQUIRE_ROBOTS();
  const TuckedPr2 robot;  // a model of its own: no thread has proven anything about it yet
  const auto empty = std::make_shared<const Environment>(0.05);
  std::mt19937_64 rng(58);
  std::vector<std::pair<std::vector<double>, std::vector<double>>> sweeps;
  const std::size_t pan = robot.variable("r_shoulder_pan_joint");
  while (sweeps.size() < 12) {
    const std::vector<double> a = robot.random_right_arm(rng);
    std::vector<double> b = a;
    b[pan] = robot.far_value(pan, a[pan], rng);
    if (robot.checker.check_self(a.data()).collision || robot.checker.check_self(b.data()).collision) continue;
    sweeps.emplace_back(a, b);
  }
  auto intervals = [&](bool held) {
    SceneCheckOptions options;
    options.environment = false;
    options.held_pairs = held;
    const SceneChecker scene(robot.checker, empty, options);
    std::size_t n = 0;
    for (const auto& [a, b] : sweeps) {
      const MotionResult r = scene.check_motion(a.data(), b.data());
      EXPECT_TRUE(r.valid);
      n += r.states_checked;
    }
    return n;
  };
  const std::size_t without = intervals(false), first = intervals(true), next = intervals(true);
  std::cout << sweeps.size() << " sweeps of the pan joint past the tucked gripper: " << without << " intervals without the proofs, "
            << first << " with them, " << next << " on the next checker\n";
  EXPECT_GE(without, 20 * sweeps.size());
  EXPECT_LE(first, 8 * sweeps.size());
  EXPECT_LE(next, 8 * sweeps.size());
}

}  // namespace
}  // namespace bvh_collision
