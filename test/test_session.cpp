// The node's ROS-free core (session/): its checkers (proxy levels joining as built, carried
// objects, the prepared scene kept), the joint states and their history, and a scan into the
// world through the robot and object filters. All without a master: on main this logic lived in
// the node and could be tested only through a running one.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <random>
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

// The grids join beside the queries, before the levels: the robot's checker starts without them
// (no start waits on their build: pr2 without an SRDF 3-6 s on one core), answers the same before
// and after, and a prepared scene kept since before they joined takes them (it was kept while the
// snapshot stayed, with the accelerators it was prepared with).
TEST(RobotCheckers, ClearanceGridsJoinBeforeTheLevelsAndChangeNoAnswer) {
  BVH_REQUIRE_ROBOTS();
  CheckerOptions none;
  none.pair_clearance_cells = 0;
  none.proxy_cache = test::proxy_cache_dir();
  const std::size_t cells = CheckerOptions().pair_clearance_cells;
  std::vector<std::string> log;
  RobotCheckers checkers(
      test::panda_as_moveit(none), {0.02}, 50000,
      [&](SessionLogLevel level, const std::string& line) {
        EXPECT_EQ(level, SessionLogLevel::kInfo) << line;
        log.push_back(line);
      },
      cells);
  const std::shared_ptr<const CollisionChecker> before = checkers.current();
  EXPECT_TRUE(before->accelerators().pair_clearance().grids().empty());
  auto env = std::make_shared<const Environment>(0.05);
  const auto scene_before = checkers.prepared(env, true, true, Transform(), 0.0);
  checkers.start_proxy_levels();
  checkers.wait_for_proxy_levels();
  const std::shared_ptr<const CollisionChecker> after = checkers.current();
  const CollisionChecker direct = test::panda_as_moveit();
  ASSERT_FALSE(direct.accelerators().pair_clearance().grids().empty());
  EXPECT_EQ(after->accelerators().pair_clearance().grids().size(), direct.accelerators().pair_clearance().grids().size());
  ASSERT_EQ(after->accelerators().proxy_levels().size(), 1u);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_NE(log[0].find("clearance grids ready"), std::string::npos) << log[0];
  EXPECT_NE(log[1].find("proxy level 0.02 m ready"), std::string::npos) << log[1];

  const auto scene_after = checkers.prepared(env, true, true, Transform(), 0.0);
  EXPECT_NE(scene_after, scene_before) << "the scene prepared before the grids and the level joined";
  EXPECT_EQ(&scene_after->checker().accelerators(), &after->accelerators());
  EXPECT_EQ(checkers.prepared(env, true, true, Transform(), 0.0), scene_after) << "then kept while nothing changes";
  std::mt19937_64 rng(17);
  int colliding = 0;
  for (int i = 0; i < test::sized(300); ++i) {
    const std::vector<double> q = random_configuration(before->model(), rng);
    const bool hit = before->check_self(q.data()).collision;
    colliding += hit;
    EXPECT_EQ(after->check_self(q.data()).collision, hit);
  }
  EXPECT_GT(colliding, 0);
  for (int i = 0; i < test::sized(60); ++i) {
    const std::vector<double> a = random_configuration(before->model(), rng), b = random_configuration(before->model(), rng);
    const MotionResult x = scene_before->check_motion(a.data(), b.data()), y = scene_after->check_motion(a.data(), b.data());
    EXPECT_EQ(x.valid, y.valid);
  }
}

// The sphere budget stops before a level predicted beyond it (a surface's cover grows as the
// inverse square of the level), not after one that already went past it.
TEST(RobotCheckers, AFinerLevelPredictedBeyondTheSphereBudgetIsNotBuilt) {
  RobotCheckers coarse = demo_checkers({0.02});
  coarse.start_proxy_levels();
  coarse.wait_for_proxy_levels();
  const std::size_t at_20mm = coarse.current()->accelerators().proxies_for(0.02)->leaves;
  ASSERT_GT(at_20mm, 10u);
  // Room for twice the 20 mm spheres: 10 mm (about four times as many) does not fit.
  std::vector<std::string> log;
  RobotCheckers checkers(test::demo_arm_checker(), {0.005, 0.01, 0.02}, 2 * at_20mm,
                         [&](SessionLogLevel, const std::string& line) { log.push_back(line); });
  checkers.start_proxy_levels();
  checkers.wait_for_proxy_levels();
  const auto& built = checkers.current()->accelerators().proxy_levels();
  ASSERT_EQ(built.size(), 1u) << "the coarsest level is always built, and only it fits";
  EXPECT_EQ(built[0].level, 0.02);
  ASSERT_EQ(log.size(), 2u);
  EXPECT_NE(log[1].find("finer proxy levels skipped: 0.01 m would need about " + std::to_string(4 * at_20mm) + " spheres"),
            std::string::npos)
      << log[1];
  // A budget the levels fit: every one built.
  RobotCheckers roomy = demo_checkers({0.005, 0.01, 0.02});
  roomy.start_proxy_levels();
  roomy.wait_for_proxy_levels();
  EXPECT_EQ(roomy.current()->accelerators().proxy_levels().size(), 3u);
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

// Every snapshot a scan publishes already holds its distance field: a query that meets it first
// finds the field kept instead of building one (before, the field was built after publication, and
// a motion asked in between built its own: at 10 Hz of clouds the demo's certified motions lost
// 89 % of their throughput, bench table live_world). A reader spinning on the store's version
// checks each new snapshot the moment it appears; the field then follows the scans' flipped voxels.
TEST(ScanUpdate, ASnapshotIsPublishedWithItsDistanceField) {
  RobotCheckers checkers = demo_checkers({});
  const CollisionChecker& checker = *checkers.current();
  EnvironmentStore store{Environment(0.02)};
  const std::vector<double> q(checker.model().variable_count(), 0.0);
  std::atomic<bool> done{false};
  std::atomic<int> seen{0}, without{0};
  int in_place = 0;
  std::thread reader([&] {
    std::uint64_t last = store.version();
    while (!done) {
      if (store.version() == last) continue;
      const std::shared_ptr<const Environment> now = store.snapshot();
      last = store.version();
      ++seen;
      if (!now->octree().empty() && checker.kept_distance_field(*now) == nullptr) ++without;
    }
  });
  std::mt19937_64 rng(9);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  for (int scan = 0; scan < 8; ++scan) {
    std::vector<ScanPoint> points;
    for (double y = -0.3; y <= 0.3; y += 0.02) {
      for (double z = 0.1; z <= 0.9; z += 0.02) points.emplace_back(0.7f + noise(rng), float(y), float(z));
    }
    const ScanUpdateResult result = update_scan(store, checkers, points, {}, ScanPoint(0.0f, -1.5f, 0.5f), q.data(), Transform(), ScanUpdateOptions{});
    EXPECT_TRUE(result.field_made) << "scan " << scan;
    // From the third scan on, the field two scans old is held by no one (the reader has moved on,
    // the store holds the last): the new one is made on it in place, with no copy of the grid.
    if (scan >= 2) {
      EXPECT_EQ(result.field.copied_cells, 0u) << "scan " << scan;
      in_place += !result.field.rebuilt;
    }
    // (The reader takes each publication before the next: it waits for the version to move.)
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (seen.load() <= scan && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
  }
  done = true;
  reader.join();
  EXPECT_EQ(seen.load(), 8);
  EXPECT_EQ(without.load(), 0);
  EXPECT_GE(in_place, 5);
  const std::shared_ptr<const Environment> now = store.snapshot();
  const auto field = checker.kept_distance_field(*now);
  ASSERT_NE(field, nullptr);
  // Equal to a build of the last map over the checker's box and cap (environment_check.cpp).
  double cap = 0.0;
  const RobotCollisionModel& m = checker.collision_model();
  for (std::size_t l = 0; l < m.bounds().size(); ++l) cap = std::max(cap, m.bounds()[l].radius + m.paddings()[l]);
  const Vec3 reach = Vec3::Constant(checker.reach());
  EXPECT_TRUE(field->same_values(OctreeDistanceField::build(now->octree(), -reach, reach, cap + 0.02)));
}

}  // namespace
}  // namespace bvh_collision
