// The node's ROS-free core (session/): its checkers (proxy levels joining as built, carried
// objects, the prepared scene kept), the joint states and their history, and a scan into the
// world through the robot and object filters. All without a master: on main this logic lived in
// the node and could be tested only through a running one.
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "bvh_collision/session/joint_states.h"
#include "bvh_collision/session/robot_checkers.h"
#include "bvh_collision/session/scan_update.h"
#include "checker_fixtures.h"

namespace bvh_collision {
namespace {

RobotCheckers demo_checkers(std::vector<double> levels, std::vector<std::string>* log = nullptr) {
  return RobotCheckers(test::demo_arm_checker(), std::move(levels), 50000, [log](SessionLogLevel, const std::string& line) {
    if (log != nullptr) log->push_back(line);
  });
}

TEST(RobotCheckers, ProxyLevelsJoinTheCheckerAsTheyAreBuilt) {
  std::vector<std::string> log;
  RobotCheckers checkers(test::demo_arm_checker(), {0.01, 0.02}, 50000, [&](SessionLogLevel level, const std::string& line) {
    EXPECT_EQ(level, SessionLogLevel::kInfo) << line;
    log.push_back(line);
  });
  const std::shared_ptr<const CollisionChecker> before = checkers.current();
  EXPECT_TRUE(before->accelerators().proxy_levels().empty());
  checkers.start_proxy_levels();
  checkers.wait_for_proxy_levels();
  const std::shared_ptr<const CollisionChecker> after = checkers.current();
  ASSERT_EQ(after->accelerators().proxy_levels().size(), 2u);
  EXPECT_NE(after->accelerators().proxies_for(0.02), nullptr);
  EXPECT_NE(after->accelerators().proxies_for(0.01), nullptr);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_NE(log[0].find("proxy level 0.02 m ready"), std::string::npos) << log[0];  // coarsest first
  EXPECT_NE(log[1].find("proxy level 0.01 m ready"), std::string::npos) << log[1];
  EXPECT_TRUE(before->accelerators().proxy_levels().empty()) << "a checker a query holds never changes";
}

TEST(RobotCheckers, ASnapshotsAttachedObjectsAreCarriedOnceAndKept) {
  RobotCheckers checkers = demo_checkers({});
  auto env = std::make_shared<Environment>(0.05);
  EXPECT_EQ(checkers.for_snapshot(env), checkers.current()) << "nothing attached: the robot's own";
  Environment held = *env;
  held.attach(AttachedBody{"parcel", "hand", {"finger_left", "finger_right"},
                           {make_collision_object("parcel", ObjectShape::box({0.08, 0.08, 0.08}), Transform::Translation({0, 0, 0.1}))}});
  const auto snapshot = std::make_shared<const Environment>(held);
  const std::shared_ptr<const CollisionChecker> carrying = checkers.for_snapshot(snapshot);
  EXPECT_GE(carrying->model().link_index("parcel"), 0);
  EXPECT_TRUE(carrying->carries(held));
  EXPECT_EQ(checkers.for_snapshot(snapshot), carrying) << "the same attachment: the kept checker";
  EXPECT_TRUE(checkers.carried_levels_built(held)) << "no proxy level to build";
  // Attached anew (another list): another checker.
  Environment again = held;
  again.detach("parcel");
  again.attach(AttachedBody{"bar", "hand", {}, {make_collision_object("bar", ObjectShape::box({0.02, 0.5, 0.02}), Transform())}});
  const auto other = checkers.for_snapshot(std::make_shared<const Environment>(again));
  EXPECT_NE(other, carrying);
  EXPECT_GE(other->model().link_index("bar"), 0);
  EXPECT_LT(other->model().link_index("parcel"), 0);
}

TEST(RobotCheckers, ThePreparedSceneIsKeptWhileNothingChanges) {
  RobotCheckers checkers = demo_checkers({});
  auto env = std::make_shared<const Environment>(0.05);
  const auto a = checkers.prepared(env, true, true, Transform(), 0.0);
  EXPECT_EQ(checkers.prepared(env, true, true, Transform(), 0.0), a);
  EXPECT_NE(checkers.prepared(env, true, true, Transform(), 0.01), a) << "another tolerance";
  const auto b = checkers.prepared(env, true, false, Transform(), 0.01);
  EXPECT_FALSE(b->options().environment);
  auto changed = std::make_shared<const Environment>(*env);
  EXPECT_NE(checkers.prepared(changed, true, false, Transform(), 0.01), b) << "another snapshot";
}

TEST(JointStates, MergeTheRobotsValuesAndAnswerAtAStamp) {
  const RobotModel model = test::demo_arm_model();
  const std::size_t n = model.variable_count();
  JointStates joints(model, std::vector<double>(n, 0.0), 10.0, 0.1);
  EXPECT_FALSE(joints.last_arrival());
  EXPECT_EQ(joints.at(5.0, 0.0), std::vector<double>(n, 0.0)) << "no history yet: the current state";
  // Another robot's joints and a non-finite value are ignored; nothing of ours: not recorded.
  EXPECT_FALSE(joints.record({"wheel", "joint1"}, {1.0, std::nan("")}, 1.0, 1.0));
  EXPECT_EQ(joints.recorded(), 0u);
  ASSERT_TRUE(joints.record({"wheel", "joint1"}, {1.0, 0.2}, 1.0, 100.0));
  ASSERT_TRUE(joints.record({"joint2"}, {0.4}, 2.0, 101.0));
  const int j1 = model.joints()[model.joint_index("joint1")].variable, j2 = model.joints()[model.joint_index("joint2")].variable;
  EXPECT_EQ(joints.current()[j1], 0.2);
  EXPECT_EQ(joints.current()[j2], 0.4);
  EXPECT_EQ(*joints.last_arrival(), 101.0);
  const std::optional<std::vector<double>> half = joints.at(1.5, 0.0);
  ASSERT_TRUE(half);
  EXPECT_DOUBLE_EQ((*half)[j1], 0.2);
  EXPECT_DOUBLE_EQ((*half)[j2], 0.2) << "halfway between 0 and 0.4";
  EXPECT_FALSE(joints.at(0.5, 0.0)) << "before the history";
  EXPECT_EQ(joints.at(0.0, 0.0), joints.current()) << "an unstamped question: the current state";
  EXPECT_THROW(joints.record({"joint1"}, {}, 3.0, 3.0), std::invalid_argument);
  // A stamp ahead of the history waits for the state that reaches it (it often comes after the
  // cloud): another thread records it while at() waits (its deadline generous, not timed).
  std::thread later([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    joints.record({"joint1"}, {0.6}, 5.0, 102.0);
  });
  const std::optional<std::vector<double>> ahead = joints.at(5.0, 30.0);
  later.join();
  ASSERT_TRUE(ahead);
  EXPECT_DOUBLE_EQ((*ahead)[j1], 0.6);
}

// A scan of a wall beside the arm, with points on the arm itself and on a known box: the arm's
// and the box's points are not voxels, the wall's are, and the new map's field is kept.
TEST(ScanUpdate, FiltersTheRobotAndKnownObjectsAndInsertsTheRest) {
  RobotCheckers checkers = demo_checkers({});
  const CollisionChecker& checker = *checkers.current();
  Environment start(0.02);
  start.add_object("crate", ObjectShape::box({0.2, 0.2, 0.2}), Transform::Translation({-0.6, 0.0, 0.3}));
  EnvironmentStore store(start);
  const std::vector<double> q(checker.model().variable_count(), 0.0);
  std::vector<Transform> poses;
  forward_kinematics(checker.model(), q.data(), poses);
  std::vector<ScanPoint> points;
  for (double y = -0.3; y <= 0.3; y += 0.02) {
    for (double z = 0.1; z <= 0.9; z += 0.02) points.emplace_back(0.7f, float(y), float(z));  // the wall
  }
  const std::size_t wall = points.size();
  const Vec3 on_link = poses[checker.model().link_index("link2")] * Vec3(0.05, 0.0, 0.2);  // link2's cylinder surface
  for (int k = 0; k < 10; ++k) points.push_back((on_link + Vec3(0, 0, 0.01 * k)).cast<float>());
  for (int k = 0; k < 10; ++k) points.emplace_back(-0.5f, float(-0.05 + 0.01 * k), 0.4f);  // the crate's top face
  ScanUpdateOptions options;
  options.scan.max_range = 5.0;
  const ScanPoint sensor(0.0f, -1.5f, 0.5f);
  const ScanUpdateResult result = update_scan(store, checkers, points, {}, sensor, q.data(), Transform(), options);
  EXPECT_GE(result.on_robot, 10u);
  EXPECT_EQ(result.on_objects, 10u);
  EXPECT_EQ(result.stats.points, points.size()) << "every ray clears; the robot's and the crate's mark nothing";
  EXPECT_GT(wall, 0u);
  const std::shared_ptr<const Environment> now = store.snapshot();
  const auto occupied = [&](const Vec3& p) { return !now->octree().occupied_in_sphere(p, 0.001, true).empty(); };
  EXPECT_TRUE(occupied(Vec3(0.7, 0.0, 0.5)));
  EXPECT_FALSE(occupied(on_link));
  EXPECT_FALSE(occupied(Vec3(-0.5, 0.0, 0.4)));
  EXPECT_NE(checker.kept_distance_field(*now), nullptr) << "the new map's field is built with it";
}

}  // namespace
}  // namespace bvh_collision
