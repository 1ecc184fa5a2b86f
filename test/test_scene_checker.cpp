// SceneChecker (query/scene_checker.h), the planner-facing path, against the checker's own
// general queries as the oracle: one state at tolerance 0 answers exactly as check_self +
// check_environment; at a tolerance every answer keeps the contract by exact distances; a
// motion asked again, or within one found free, is answered from the thread's memory for its
// checker only; the object grid offers every object a ball meets. Scenes are the planning
// benchmark's (test/planning_scenes.h) on panda, and an octree pillar on the demo arm. The
// certified motions' tests are in test_scene_motion.cpp (the same binary).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "bvh_collision/world/object_grid.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"
#include "scene_checker_fixtures.h"
#include "advancement_oracle.h"

namespace bvh_collision {
namespace {

using scene_test::exact_clearance;
using scene_test::exact_collides;
using scene_test::panda;

TEST(SceneChecker, StatesAnswerAsTheGeneralQueries) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(5);
  std::size_t states = 0, colliding = 0, within = 0;
  for (int scene = 0; scene < 4; ++scene) {
    const auto env = std::make_shared<const Environment>(test::generate_scene(11, scene).environment());
    const SceneChecker exact(checker, env);
    SceneCheckOptions at_1cm;
    at_1cm.tolerance = 0.01;
    const SceneChecker planner(checker, env, at_1cm);  // states exact (the default)
    at_1cm.states_at_tolerance = true;
    const SceneChecker coarse(checker, env, at_1cm);
    for (int i = 0; i < test::sized(400); ++i, ++states) {
      const std::vector<double> q = random_configuration(checker.model(), rng);
      const bool truth = exact_collides(checker, q.data(), *env);
      colliding += truth;
      ASSERT_EQ(exact.collides(q.data()), truth) << "scene " << scene << " state " << i;
      ASSERT_EQ(planner.collides(q.data()), truth) << "scene " << scene << " state " << i;
      // At 1 cm: collision whenever it collides, free whenever clearance exceeds 1 cm.
      const bool answer = coarse.collides(q.data());
      if (truth) {
        ASSERT_TRUE(answer) << "scene " << scene << " state " << i;
      } else if (answer) {
        const double clearance = exact_clearance(checker, q.data(), *env);
        ASSERT_LE(clearance, 0.01 + 1e-9) << "scene " << scene << " state " << i;
        ++within;
      }
    }
  }
  std::cout << states << " states, " << colliding << " colliding; at 1 cm " << within
            << " free ones answered colliding, all within 1 cm\n";
  EXPECT_GT(colliding, states / 10);  // the scenes are cluttered enough to test both answers
  EXPECT_LT(colliding, states - states / 10);
}

// A state's components are sieved 64 at a time (check_still). Panda's fit in one block; PR2 (some
// fifty links with geometry, hundreds of checked pairs once its SRDF's are allowed) spans
// several. Each state answers as the general queries, self pairs alone and with objects.
TEST(SceneChecker, StatesOfARobotOfManyBlocksAnswerAsTheGeneralQueries) {
  BVH_REQUIRE_ROBOTS();
  static const CollisionChecker checker = test::load_as_moveit("pr2");
  const auto& shapes = checker.collision_model().shapes();
  const std::size_t links = static_cast<std::size_t>(std::count_if(shapes.begin(), shapes.end(), [](const auto& s) { return !s.empty(); }));
  const std::size_t components = checker.collision_model().checked_pairs().size() + links;
  ASSERT_GT(components, 4u * 64u) << "the sieve's blocks are what this test is for";
  std::mt19937_64 rng(17);
  std::size_t states = 0, colliding = 0, self_colliding = 0;
  for (int scene = 0; scene < 2; ++scene) {
    // Boxes, spheres and cylinders in front of PR2, around the height of its arms.
    Environment world(0.05);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int o = 0; o < 12; ++o) {
      const Vec3 at(0.45 + 0.5 * unit(rng), -0.7 + 1.4 * unit(rng), 0.5 + 0.7 * unit(rng));
      const double size = 0.04 + 0.12 * unit(rng);
      const ObjectShape shape = o % 3 == 0 ? ObjectShape::box(Vec3(size, 2 * size, size / 2))
                                : o % 3 == 1 ? ObjectShape::sphere(size / 2)
                                             : ObjectShape::cylinder(size / 3, 2 * size);
      world.add_object("object_" + std::to_string(o), shape, Transform{Eigen::AngleAxisd(3.0 * unit(rng), Vec3(unit(rng), unit(rng), 0.5).normalized()).toRotationMatrix(), at});
    }
    const auto env = std::make_shared<const Environment>(world);
    SceneCheckOptions placed;
    placed.root_pose = Transform::Translation(Vec3(0.02, -0.03, 0.01));  // (not the identity: the poses' product)
    const SceneChecker both(checker, env, placed);
    placed.environment = false;
    const SceneChecker self(checker, env, placed);
    for (int i = 0; i < test::sized(150); ++i, ++states) {
      // Every other state within half a radian of the zero pose (a random PR2 pose nearly always
      // folds its arms into its body).
      std::vector<double> q = random_configuration(checker.model(), rng);
      if (i % 2 == 0) {
        for (double& v : q) v *= 0.5 / M_PI;
      }
      const bool self_truth = checker.check_self(q.data()).collision;
      EnvironmentRequest request;
      request.contacts = false;
      request.root_pose = placed.root_pose;
      const bool truth = self_truth || checker.check_environment(q.data(), *env, request).collision;
      colliding += truth;
      self_colliding += self_truth;
      ASSERT_EQ(self.collides(q.data()), self_truth) << "scene " << scene << " state " << i;
      ASSERT_EQ(both.collides(q.data()), truth) << "scene " << scene << " state " << i;
    }
  }
  std::cout << states << " PR2 states, " << colliding << " colliding, " << self_colliding << " with itself\n";
  EXPECT_GT(self_colliding, states / 20);     // the pairs' blocks decide some
  EXPECT_GT(colliding - self_colliding, states / 20);  // and the links' some
  EXPECT_GT(states - colliding, states / 10);
}

// A state found free is remembered by the thread (a planner asks for it again as the start of
// its motions) and answered from memory only by the checker that found it: not by another one
// alive beside it, nor by one built in the same storage after it (a pointer would call those the
// same checker), whose box now holds the hand.
TEST(SceneChecker, AStateRememberedFreeAnswersOnlyForItsChecker) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  auto variable = [&](const std::string& joint) { return static_cast<std::size_t>(model.joints()[model.joint_index(joint)].variable); };
  std::vector<double> q(model.variable_count(), 0.02);  // the fingers half open
  const double ready[] = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  for (int j = 0; j < 7; ++j) q[variable("panda_joint" + std::to_string(j + 1))] = ready[j];
  std::vector<double> next = q;
  next[variable("panda_joint1")] = 0.3;
  std::vector<Transform> poses;
  forward_kinematics(model, q.data(), poses);
  const Vec3 hand = poses[model.link_index("panda_hand")].t;
  const auto empty = std::make_shared<const Environment>(Environment(0.05));
  Environment world(0.05);
  world.add_object("box", ObjectShape::box({0.1, 0.1, 0.1}), Transform::Translation(hand));
  const auto boxed = std::make_shared<const Environment>(world);

  std::optional<SceneChecker> scene;
  scene.emplace(checker, empty);
  ASSERT_FALSE(scene->collides(q.data()));
  ASSERT_FALSE(scene->collides(q.data()));  // from memory
  ASSERT_TRUE(scene->check_motion(q.data(), next.data()).valid);
  const SceneChecker beside(checker, boxed);
  EXPECT_TRUE(beside.collides(q.data()));
  EXPECT_FALSE(scene->collides(q.data()));
  const SceneChecker* before = &*scene;
  scene.emplace(checker, boxed);  // the first destroyed, the second built where it stood
  ASSERT_EQ(before, &*scene);
  EXPECT_TRUE(scene->collides(q.data()));
  const MotionResult r = scene->check_motion(q.data(), next.data());
  EXPECT_FALSE(r.valid);
  EXPECT_EQ(r.colliding_fraction, 0.0);
}

// A motion asked again (OMPL's simplifier asked 3,295 of the benchmark's 21,334 motions again) is
// answered from the thread's memory: the answer the check gave, with no interval checked; only
// for the same checker, the same kind of question (boolean or earliest) and the same ends bit for
// bit. Checked against a second checker of the same scene, which has no memory of these motions,
// over random motions in a planning scene, asked in rounds of 50 (100 questions: slots are shared
// and reused).
bool same_answer(const MotionResult& a, const MotionResult& b) {
  return a.valid == b.valid && a.certified == b.certified && a.colliding_fraction == b.colliding_fraction &&
         a.last_valid_fraction == b.last_valid_fraction && a.message == b.message;
}

TEST(SceneChecker, AMotionAskedAgainIsAnsweredFromMemory) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const auto env = std::make_shared<const Environment>(test::generate_scene(11, 12).environment());
  const auto empty = std::make_shared<const Environment>(Environment(0.05));
  SceneCheckOptions options;
  options.tolerance = 0.01;
  const SceneChecker scene(checker, env, options), fresh(checker, env, options), other(checker, empty, options);
  std::mt19937_64 rng(29);
  std::size_t questions = 0, remembered = 0, colliding = 0;
  for (int round = 0; round < 6; ++round) {
    std::vector<std::vector<double>> states;
    states.push_back(random_configuration(checker.model(), rng));
    while (states.size() < 51) {  // steps a fifth of the way to a random state: some free, some not
      std::vector<double> q = random_configuration(checker.model(), rng);
      for (std::size_t j = 0; j < q.size(); ++j) q[j] = states.back()[j] + 0.2 * (q[j] - states.back()[j]);
      states.push_back(q);
    }
    std::vector<MotionResult> first;  // boolean, then earliest, per motion
    for (std::size_t i = 0; i + 1 < states.size(); ++i) {
      for (const bool earliest : {false, true}) {
        first.push_back(scene.check_motion(states[i].data(), states[i + 1].data(), earliest));
        // Never asked before (the earliest collision of a motion just found free lies within it:
        // answered from memory, AMotionWithinOneFoundFreeIsAnsweredFromMemory).
        if (earliest && first[first.size() - 2].valid) {
          ASSERT_EQ(first.back().states_checked, 0u) << "motion " << i;
        } else {
          ASSERT_GT(first.back().states_checked, 0u) << "motion " << i;
        }
        colliding += !first.back().valid;
      }
    }
    for (std::size_t i = 0; i + 1 < states.size(); ++i) {
      for (const bool earliest : {false, true}) {
        const MotionResult& before = first[2 * i + earliest];
        const MotionResult again = scene.check_motion(states[i].data(), states[i + 1].data(), earliest);
        ASSERT_TRUE(same_answer(again, before)) << "motion " << i;
        ASSERT_TRUE(same_answer(fresh.check_motion(states[i].data(), states[i + 1].data(), earliest), before)) << "motion " << i;
        remembered += again.states_checked == 0;
        ++questions;
      }
    }
    for (std::size_t i = 0; i + 1 < states.size(); ++i) {
      // Another scene asked the same motion answers for its own scene, from its own check.
      EXPECT_GT(other.check_motion(states[i].data(), states[i + 1].data()).states_checked, 0u) << "motion " << i;
      // Ends one bit apart are another motion (a free one's: a micro-radian apart, off the segment
      // remembered free, which holds motions within it: AMotionWithinOneFoundFreeIsAnsweredFromMemory).
      std::vector<double> goal = states[i + 1];
      goal[0] = first[2 * i].valid ? goal[0] + 1e-6 : std::nextafter(goal[0], 10.0);
      EXPECT_GT(scene.check_motion(states[i].data(), goal.data()).states_checked, 0u) << "motion " << i;
      // Asked back to back, a motion is always remembered.
      const MotionResult b = scene.check_motion(states[i].data(), goal.data());
      EXPECT_EQ(b.states_checked, 0u) << "motion " << i;
      EXPECT_TRUE(same_answer(b, fresh.check_motion(states[i].data(), goal.data()))) << "motion " << i;
    }
  }
  std::cout << remembered << " of " << questions << " motions asked again were answered from memory; " << colliding
            << " of them collide\n";
  EXPECT_GT(colliding, questions / 10);
  EXPECT_LT(colliding, questions - questions / 10);
  EXPECT_GT(remembered, questions / 2);  // the rest: their slot taken by a later question of the round
}

// OMPL's path simplifier asks for motions between states it put on segments found free (its
// B-spline pass subdivides the path; it checks the path again after each pass): a motion within a
// segment this thread certified free with this checker is free, answered from memory. Within
// means both ends on the segment to within rounding (kOnSegment, 1e-13 a variable); beyond that,
// past an end, from another checker, or within a colliding motion, the motion is checked. Every
// answer from memory is checked free by a checker that never saw the segment. A motion from or to
// a state on the segment (that end answered free by it) answers as that checker does.
TEST(SceneChecker, AMotionWithinOneFoundFreeIsAnsweredFromMemory) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const auto env = std::make_shared<const Environment>(test::generate_scene(11, 12).environment());
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::size_t n = checker.model().variable_count();
  auto along = [&](const std::vector<double>& p, const std::vector<double>& q, double t) {
    std::vector<double> s(n);
    for (std::size_t j = 0; j < n; ++j) s[j] = p[j] + (q[j] - p[j]) * t;  // as OMPL interpolates
    return s;
  };
  for (const double tolerance : {0.0, 0.01}) {
    SceneCheckOptions options;
    options.tolerance = tolerance;
    const SceneChecker scene(checker, env, options), fresh(checker, env, options), other(checker, env, options);
    const std::size_t wanted_free = static_cast<std::size_t>(test::sized(24)), wanted_colliding = static_cast<std::size_t>(test::sized(8));
    std::size_t free = 0, colliding = 0, within = 0, colliding_ends = 0;
    while (free < wanted_free || colliding < wanted_colliding) {
      const std::vector<double> p = random_configuration(checker.model(), rng);
      const std::vector<double> q = along(p, random_configuration(checker.model(), rng), 0.2);
      const MotionResult whole = scene.check_motion(p.data(), q.data());
      ASSERT_GT(whole.states_checked, 0u);
      if (!whole.valid && colliding >= wanted_colliding) continue;
      (whole.valid ? free : colliding) += 1;
      for (int k = 0; k < (whole.valid ? 6 : 1); ++k) {
        double t0 = unit(rng), t1 = unit(rng);
        if (k == 0) t0 = 0.0, t1 = 1.0 - 1e-3;  // from an end; then backwards, then random pieces
        if (k == 1) t0 = 1.0, t1 = 0.25;
        const std::vector<double> a = along(p, q, t0), b = along(p, q, t1);
        const MotionResult piece = scene.check_motion(a.data(), b.data(), k % 2 == 1);
        if (!whole.valid) {  // a colliding motion leaves nothing in memory
          EXPECT_GT(piece.states_checked, 0u);
          EXPECT_TRUE(same_answer(piece, fresh.check_motion(a.data(), b.data())));
          continue;
        }
        ASSERT_EQ(piece.states_checked, 0u) << tolerance << " " << t0 << " " << t1;
        ASSERT_TRUE(piece.valid && piece.certified && piece.last_valid_fraction == 1.0);
        // Conservative advancement (another algorithm, exact) finds it free too.
        MotionRequest exact;
        exact.max_states = 200000;
        ASSERT_TRUE(test::advancement_motion(checker, a.data(), b.data(), *env, exact).valid) << "a piece of a free motion collides: " << t0 << " " << t1;
        ++within;
      }
      if (!whole.valid) continue;
      // Off the segment: past its end, a variable beyond rounding off it, another checker.
      const std::vector<double> past = along(p, q, 1.05), half = along(p, q, 0.5);
      EXPECT_GT(scene.check_motion(p.data(), past.data()).states_checked, 0u);
      std::vector<double> near = half, off = half;
      near[1] += 5e-14;  // within kOnSegment: panda's links move less than 1e-12 m for it
      off[1] += 1e-12;
      EXPECT_EQ(scene.check_motion(p.data(), near.data()).states_checked, 0u);
      const MotionResult beside = scene.check_motion(p.data(), off.data());
      EXPECT_GT(beside.states_checked, 0u);
      EXPECT_TRUE(same_answer(beside, fresh.check_motion(p.data(), off.data())));
      EXPECT_GT(other.check_motion(half.data(), q.data()).states_checked, 0u);
      // From a state on the segment (its end check answered by the segment) to anywhere: the
      // answer a checker that never saw the segment gives.
      const std::vector<double> on = along(p, q, unit(rng)), elsewhere = random_configuration(checker.model(), rng);
      // (Both checkers run the same code: a motion from a colliding state must also collide at
      // its start, and a free one be free by conservative advancement.)
      const bool elsewhere_collides = fresh.collides(elsewhere.data());
      colliding_ends += elsewhere_collides;
      for (const bool earliest : {false, true}) {
        const MotionResult away = scene.check_motion(on.data(), elsewhere.data(), earliest);
        const MotionResult back = scene.check_motion(elsewhere.data(), on.data(), earliest);
        EXPECT_TRUE(same_answer(away, fresh.check_motion(on.data(), elsewhere.data(), earliest)));
        EXPECT_TRUE(same_answer(back, fresh.check_motion(elsewhere.data(), on.data(), earliest)));
        if (elsewhere_collides) {
          EXPECT_FALSE(back.valid);
          EXPECT_EQ(back.colliding_fraction, 0.0);
        }
        if (away.valid) {
          MotionRequest exact;
          exact.max_states = 200000;
          EXPECT_TRUE(test::advancement_motion(checker, on.data(), elsewhere.data(), *env, exact).valid);
        }
      }
      EXPECT_FALSE(scene.collides(on.data()));
    }
    std::cout << "tolerance " << tolerance << ": " << within << " motions within " << free << " free ones answered from memory; "
              << colliding << " colliding motions' pieces checked\n";
    EXPECT_GT(colliding_ends, 0u);
  }
}

// A state with a value that is not a number or infinite has no pose: every query of one refuses
// it by name, never answers it (the poses would be NaN, and NaN compares as apart; a self pair's
// mesh walk then sends every triangle pair to the exact predicates, for minutes). Each variable
// in turn, the hand among boxes; the state remembered free first, so that memory cannot answer.
TEST(SceneChecker, RefusesAStateNotFinite) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  Environment world(0.05);
  for (int i = 0; i < 8; ++i) world.add_object("box" + std::to_string(i), ObjectShape::box({0.2, 0.2, 0.2}), Transform::Translation(Vec3(0.3 * (i % 4) - 0.45, 0.5 * (i / 4) - 0.25, 0.5)));
  const SceneChecker scene(checker, std::make_shared<const Environment>(world));
  std::vector<double> q(model.variable_count(), 0.02);
  const double ready[] = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  for (int j = 0; j < 7; ++j) q[static_cast<std::size_t>(model.joints()[model.joint_index("panda_joint" + std::to_string(j + 1))].variable)] = ready[j];
  ASSERT_FALSE(scene.collides(q.data()));
  for (std::size_t v = 0; v < q.size(); ++v) {
    for (const double bad : {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()}) {
      std::vector<double> r = q;
      r[v] = bad;
      // The planner's path, and every query of CollisionChecker that takes a state.
      const std::vector<std::pair<const char*, std::function<void()>>> queries = {
          {"collides", [&] { scene.collides(r.data()); }},
          {"scene motion", [&] { scene.check_motion(q.data(), r.data()); }},
          {"check_self", [&] { checker.check_self(r.data()); }},
          {"check_environment", [&] { checker.check_environment(r.data(), scene.environment()); }},
          {"check_batch", [&] { checker.check_batch(r.data(), 1, &scene.environment(), BatchRequest{}); }},
          {"check_motion", [&] { checker.check_motion(r.data(), q.data(), scene.environment(), MotionRequest{}); }},
          {"cast_ray", [&] { checker.cast_ray(r.data(), scene.environment(), Vec3::Zero(), Vec3::UnitX(), 1.0); }},
      };
      for (const auto& [name, query] : queries) {
        try {
          query();
          ADD_FAILURE() << name << ": " << model.variable_names()[v] << " = " << bad << " was answered";
        } catch (const std::invalid_argument& e) {
          EXPECT_NE(std::string(e.what()).find(model.variable_names()[v] + " is not finite"), std::string::npos) << name << ": " << e.what();
        }
      }
    }
  }
}

// The inscribed depth that proves a link point inside an object: around a point it reports
// depth d for, every point within d is inside the primitive (contains(), by sampled directions),
// and the bound is tight (some point just beyond d is outside), but for the cone, where it is a
// lower bound (the slant measured to its whole line).
TEST(SceneChecker, InscribedDepthIsTheLargestBallInside) {
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const std::vector<Primitive> shapes = {Primitive::box({0.3, 0.1, 0.6}), Primitive::sphere(0.2), Primitive::cylinder(0.05, 0.4),
                                         Primitive::capsule(0.07, 0.3), Primitive::cone(0.1, 0.2), Primitive::cone(0.3, 0.1)};
  int inside = 0;
  for (const Primitive& prim : shapes) {
    const Vec3 half = half_extents(prim);
    for (int i = 0; i < 400; ++i) {
      const Vec3 p(unit(rng) * half.x(), unit(rng) * half.y(), unit(rng) * half.z());
      const double d = inscribed_depth(prim, p);
      if (!contains(prim, p)) {
        EXPECT_LE(d, 1e-12) << primitive_name(prim.kind);
        continue;
      }
      ++inside;
      ASSERT_GE(d, -1e-12) << primitive_name(prim.kind);
      bool leaves = false;
      for (int k = 0; k < 200; ++k) {
        const Vec3 u = Vec3(unit(rng), unit(rng), unit(rng)).normalized();
        ASSERT_TRUE(contains(prim, p + u * (d * (1 - 1e-9)))) << primitive_name(prim.kind) << " depth " << d;
      }
      if (prim.kind == Primitive::Kind::kCone) continue;
      // Towards the nearest surface point of the boundary: the axes, and the radial direction.
      std::vector<Vec3> towards = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
      if (p.head<2>().norm() > 0) towards.push_back(Vec3(p.x(), p.y(), 0.0).normalized());
      if (p.norm() > 0) towards.push_back(p.normalized());
      const Vec3 on_axis(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      if ((p - on_axis).norm() > 0) towards.push_back((p - on_axis).normalized());
      for (const Vec3& u : towards) leaves = leaves || !contains(prim, p + u * (d + 1e-9));
      EXPECT_TRUE(leaves) << primitive_name(prim.kind) << ": depth " << d << " is not the largest";
    }
  }
  EXPECT_GT(inside, 600);
  // On the cone's axis the slant's line is the surface: the depth is exact there.
  const double slope = 0.1 / 0.2;
  EXPECT_NEAR(inscribed_depth(Primitive::cone(0.1, 0.2), Vec3::Zero()), 0.1 * slope / std::sqrt(1 + slope * slope), 1e-15);
}

// An octree obstacle: the demo arm around a pillar of voxels, exact and at 1 cm.
TEST(SceneChecker, OctreeStatesAnswerAsTheGeneralQueries) {
  CheckerOptions options;
  options.proxy_levels = {0.01, 0.02};
  const CollisionChecker checker = test::demo_arm_checker(options);
  Environment world(0.02);
  for (double z = 0.0; z < 1.0; z += 0.01) {
    for (double x = 0.3; x < 0.4; x += 0.01) {
      for (double y = -0.05; y < 0.05; y += 0.01) world.octree().update(*world.octree().grid().key(Vec3(x, y, z)), true);
    }
  }
  const auto env = std::make_shared<const Environment>(world);
  const SceneChecker exact(checker, env);
  SceneCheckOptions at_1cm;
  at_1cm.tolerance = 0.01;
  at_1cm.states_at_tolerance = true;
  const SceneChecker coarse(checker, env, at_1cm);
  std::mt19937_64 rng(17);
  int colliding = 0;
  for (int i = 0; i < test::sized(400); ++i) {
    const std::vector<double> q = random_configuration(checker.model(), rng);
    const bool truth = exact_collides(checker, q.data(), *env);
    colliding += truth;
    ASSERT_EQ(exact.collides(q.data()), truth) << "state " << i;
    if (truth) {
      ASSERT_TRUE(coarse.collides(q.data()));
    } else if (coarse.collides(q.data())) {
      ASSERT_LE(exact_clearance(checker, q.data(), *env), 0.01 + 1e-9);
    }
  }
  EXPECT_GT(colliding, 10);
}

// The object grid passes over an object of a cell's list only when its bound proves that no ball
// centred in the cell and that small meets it: every object whose own ball test passes
// (ObjectGrid::ball_meets, true whenever the ball meets it, the oracle here over every object)
// is offered, for balls anywhere in the grid up to its reach, and for balls within a hair of
// touching an object (the radius found by bisection on the ball test), turned primitives of every
// kind and mesh objects among them. A ball the grid calls clear (ObjectGrid::clear) meets none.
// `count` objects turned and placed at random within a metre of the origin, of the first `kinds`
// of: box, sphere, cylinder, capsule, cone, mesh (in turn).
Environment random_objects(std::mt19937_64& rng, int count, int kinds) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Environment world(0.05);
  for (int i = 0; i < count; ++i) {
    const Transform pose = test::random_rotation(rng, Vec3(unit(rng) * 2 - 1, unit(rng) * 2 - 1, unit(rng) * 2 - 1));
    const double a = 0.02 + 0.2 * unit(rng), b = 0.02 + 0.2 * unit(rng);
    const ObjectShape shapes[] = {ObjectShape::box({a, b, 0.3 * a}), ObjectShape::sphere(a), ObjectShape::cylinder(a, b),
                                  ObjectShape::capsule(a, b), ObjectShape::cone(a, b),
                                  ObjectShape::triangles(test::bumpy_sphere(rng, a, 5, 7, 0.2))};
    world.add_object("o" + std::to_string(i), shapes[i % kinds], pose);
  }
  return world;
}

TEST(ObjectGrid, OffersEveryObjectABallMeets) {
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Environment world = random_objects(rng, 48, 6);
  const double reach = 0.3;
  const ObjectGrid grid(world.objects(), Vec3::Constant(-1.2), Vec3::Constant(1.2), reach, 0.1);
  const int n = static_cast<int>(world.objects().size());
  int met = 0, offered_in_vain = 0, cleared = 0;
  auto expect_offered = [&](const Vec3& c, double r) {
    std::vector<char> offered(n, 0);
    grid.for_each_near(c, r, [&](int o) { offered[o] = 1; });
    const bool clear = grid.clear(c, r);  // (the state check's shortcut: nothing offered)
    cleared += clear;
    for (int o = 0; o < n; ++o) {
      if (grid.ball_meets(o, c, r)) {
        ++met;
        ASSERT_TRUE(offered[o]) << "object " << o << ", ball at " << c.transpose() << " radius " << r;
        ASSERT_FALSE(clear) << "object " << o << ", ball at " << c.transpose() << " radius " << r;
      } else if (offered[o]) {
        ++offered_in_vain;
      }
    }
  };
  for (int i = 0; i < 4000; ++i) {
    const Vec3 c(unit(rng) * 2.4 - 1.2, unit(rng) * 2.4 - 1.2, unit(rng) * 2.4 - 1.2);
    ASSERT_NO_FATAL_FAILURE(expect_offered(c, reach * unit(rng)));
    // Touching object o within a hair: the least radius its ball test passes at, by bisection.
    const int o = static_cast<int>(rng() % n);
    double lo = 0.0, hi = reach;
    if (!grid.ball_meets(o, c, hi)) continue;
    for (int k = 0; k < 60; ++k) (grid.ball_meets(o, c, 0.5 * (lo + hi)) ? hi : lo) = 0.5 * (lo + hi);
    for (const double r : {lo, hi, hi * (1 + 1e-12), lo * (1 - 1e-12)}) {
      ASSERT_NO_FATAL_FAILURE(expect_offered(c, r));
    }
  }
  EXPECT_GT(met, 1000);
  EXPECT_LT(offered_in_vain, 3 * met);  // the cells' bounds pass over most of their lists
  EXPECT_GT(cleared, 1000);
}

// A walk that carries its balls into a primitive's frame at once (ObjectGrid::local_ball_meets,
// local_depth) answers as the world tests do, against closed forms of the point's distance and
// depth: a ball that meets the primitive (its centre within the radius of it) is always reported,
// one a micrometre beyond never is, and the depth is never more than the point's; for balls
// placed by a link pose and carried by to_local(o) * pose, as scene_checker's walk places them.
TEST(ObjectGrid, BallsInAPrimitivesFrameAnswerAsInTheWorld) {
  std::mt19937_64 rng(47);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Environment world = random_objects(rng, 40, 4);
  const ObjectGrid grid(world.objects(), Vec3::Constant(-1.2), Vec3::Constant(1.2), 0.3, 0.1);
  int met = 0, missed = 0;
  for (int i = 0; i < 20000; ++i) {
    const int o = static_cast<int>(rng() % world.objects().size());
    ASSERT_TRUE(grid.exact_ball_test(o));
    const Transform link = test::random_rotation(rng, Vec3(unit(rng) * 2 - 1, unit(rng) * 2 - 1, unit(rng) * 2 - 1));
    // Near the object (within 5 cm of its box), given in the link's frame.
    const double extent = world.objects()[o].bound_radius + 0.05;
    const Vec3 near = world.objects()[o].pose * (Vec3(unit(rng) * 2 - 1, unit(rng) * 2 - 1, unit(rng) * 2 - 1) * extent);
    const Vec3 centre_in_link = link.inverse() * near;
    const Vec3 world_centre = link * centre_in_link;
    const Vec3 local = (grid.to_local(o) * link) * centre_in_link;
    const Vec3 q = world.objects()[o].pose.inverse() * world_centre;  // the oracle's own carry
    const ShapeRef exact = exact_shape_of(world.objects()[o]);
    const Primitive p = *exact_primitive(exact);
    double distance = 0.0, depth = 0.0;
    switch (p.kind) {
      case Primitive::Kind::kBox:
        distance = (q.cwiseAbs() - p.half).cwiseMax(0.0).norm();
        depth = (p.half - q.cwiseAbs()).minCoeff();
        break;
      case Primitive::Kind::kSphere:
        distance = std::max(0.0, q.norm() - p.radius);
        depth = p.radius - q.norm();
        break;
      case Primitive::Kind::kCylinder:
        distance = std::hypot(std::max(0.0, std::hypot(q.x(), q.y()) - p.radius), std::max(0.0, std::abs(q.z()) - p.half_length));
        depth = std::min(p.radius - std::hypot(q.x(), q.y()), p.half_length - std::abs(q.z()));
        break;
      default: {  // capsule
        const double z = std::clamp(q.z(), -p.half_length, p.half_length);
        distance = std::max(0.0, (q - Vec3(0, 0, z)).norm() - p.radius);
        depth = p.radius - (q - Vec3(0, 0, z)).norm();
      }
    }
    const double margin = pose_margin(link.t.norm() + centre_in_link.norm());
    for (const double r : {0.0, 0.01, 0.1 * unit(rng)}) {
      const bool meets = grid.local_ball_meets(o, local, r, margin);
      if (distance <= r) {
        ++met;
        ASSERT_TRUE(meets) << "object " << o << " distance " << distance << " radius " << r;
      } else if (distance > r + 1e-6) {
        ++missed;
        ASSERT_FALSE(meets) << "object " << o << " distance " << distance << " radius " << r;
      }
    }
    ASSERT_LE(grid.local_depth(o, local, margin), std::max(depth, 0.0) + 1e-15) << "object " << o;
    if (depth > 1e-6) {
      EXPECT_GT(grid.local_depth(o, local, margin), depth - 1e-6) << "object " << o;
    }
  }
  EXPECT_GT(met, 2000);
  EXPECT_GT(missed, 2000);
}

// Regression (make fuzz, a check_motion request): an object whose box spans more cells than an
// int counts (a box of the largest size an object may have over cells of 0.1 mm) is listed in
// every cell of the grid, not in the first one only (the cell range cast to int was undefined, and
// on x86 the first cell); one as far away is in none.
TEST(ObjectGrid, AnObjectSpanningMoreCellsThanAnIntCountsIsInEveryCell) {
  Environment world(0.05);
  world.add_object("huge", ObjectShape::box(Vec3::Constant(1e6)), Transform());
  world.add_object("far", ObjectShape::sphere(1.0), Transform::Translation(Vec3(1e6, -1e6, 1e6)));
  const ObjectGrid grid(world.objects(), Vec3::Constant(-1e-3), Vec3::Constant(1e-3), 1e-4, 1e-4);
  for (const Vec3& c : {Vec3(-9e-4, -9e-4, -9e-4), Vec3(0.0, 0.0, 0.0), Vec3(9e-4, 9e-4, 9e-4), Vec3(9e-4, -9e-4, 5e-4)}) {
    std::vector<int> offered;
    grid.for_each_near(c, 5e-5, [&](int o) { offered.push_back(o); });
    EXPECT_EQ(offered, std::vector<int>{0}) << "ball at " << c.transpose();
    EXPECT_FALSE(grid.clear(c, 5e-5)) << "ball at " << c.transpose();
  }
}

}  // namespace
}  // namespace bvh_collision
