// SceneChecker (checker/scene_checker.h), the planner-facing path, against the checker's own
// general queries as the oracle: one state at tolerance 0 answers exactly as check_self +
// check_environment; at a tolerance every answer keeps the contract by exact distances; the
// interval growth holds every vertex of every link over sampled motion; a certified motion
// answered free is free at every state of a dense sweep, and one answered colliding collides (at
// the tolerance) where it says. Scenes are the planning benchmark's (test/planning_scenes.h) on
// panda, and an octree pillar on the demo arm.
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

#include "bvh_collision/checker/object_grid.h"
#include "bvh_collision/checker/scene_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

// Panda as MoveIt sets it up, with the node's proxy levels.
const CollisionChecker& panda() { return test::panda_with_proxies(); }

// Panda as above with every link padded by `padding`, no proxy levels (exact booleans only).
const CollisionChecker& padded(double padding) {
  static std::map<double, CollisionChecker> checkers;
  auto it = checkers.find(padding);
  if (it == checkers.end()) {
    CheckerOptions options;
    options.padding = padding;  // (a self pair then by twice that: both links)
    it = checkers.emplace(padding, test::panda_as_moveit(options)).first;
  }
  return it->second;
}

// Link poses at fraction s of the straight segment from a to b.
std::vector<Transform> poses_along(const RobotModel& model, const std::vector<double>& a, const std::vector<double>& b, double s) {
  std::vector<double> q(a.size());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + s * (b[j] - a[j]);
  std::vector<Transform> poses;
  forward_kinematics(model, q.data(), poses);
  return poses;
}

// The smallest distance less padding over self pairs and obstacles (<= 0: in collision), exact.
double exact_clearance(const CollisionChecker& checker, const double* q, const Environment& env) {
  SelfCollisionRequest self;
  self.distance = true;
  const SelfCollisionResult s = checker.check_self(q, self);
  if (s.collision) return 0.0;
  EnvironmentRequest request;
  request.distance = true;
  request.contacts = false;
  const EnvironmentResult e = checker.check_environment(q, env, request);
  if (e.collision) return 0.0;
  return std::min(s.min_distance, e.min_distance);  // panda has no padding here
}

bool exact_collides(const CollisionChecker& checker, const double* q, const Environment& env) {
  EnvironmentRequest request;
  request.contacts = false;
  return checker.check_self(q).collision || checker.check_environment(q, env, request).collision;
}

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
// answer from memory is checked free by a checker that never saw the segment.
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
    std::size_t free = 0, colliding = 0, within = 0;
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
        // The general certified motion (another code path, exact) finds it free too.
        MotionRequest exact;
        exact.max_states = 200000;
        ASSERT_TRUE(checker.check_motion(a.data(), b.data(), *env, exact).valid) << "a piece of a free motion collides: " << t0 << " " << t1;
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
    }
    std::cout << "tolerance " << tolerance << ": " << within << " motions within " << free << " free ones answered from memory; "
              << colliding << " colliding motions' pieces checked\n";
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

// Every vertex of every link at any instant of an interval lies within the link's growth of
// where it is at the interval's midpoint. A rigid displacement is affine in the point, so its
// length is convex and largest at a vertex of the link's hull: vertices prove it for every point.
TEST(SceneChecker, IntervalGrowthHoldsEveryVertex) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const auto env = std::make_shared<const Environment>(0.05);
  const SceneChecker scene(checker, env);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double tightest = 0.0;
  for (int i = 0; i < test::sized(60); ++i) {
    const std::vector<double> a = random_configuration(model, rng), b = random_configuration(model, rng);
    const double lo = unit(rng), hi = lo + (1.0 - lo) * unit(rng), mid = 0.5 * (lo + hi);
    auto at = [&](double s) { return poses_along(model, a, b, s); };
    const std::vector<Transform> centre = at(mid);
    for (int k = 0; k <= 10; ++k) {
      const std::vector<Transform> poses = at(lo + (hi - lo) * k / 10.0);
      for (std::size_t l = 0; l < poses.size(); ++l) {
        const double growth = scene.link_growth(static_cast<int>(l), a.data(), b.data(), lo, hi);
        for (const CollisionElement& e : model.links()[l].collision) {
          for (const Vec3& v : e.mesh->vertices) {
            const double moved = (poses[l] * (e.origin * v) - centre[l] * (e.origin * v)).norm();
            ASSERT_LE(moved, growth) << "link " << model.links()[l].name << " case " << i;
            if (growth > 0) tightest = std::max(tightest, moved / growth);
          }
        }
      }
    }
  }
  std::cout << "largest vertex displacement / growth: " << tightest << "\n";
  EXPECT_GT(tightest, 0.05);  // the bound is not vacuous
}

// The bound follows the arm's pose: over a planner's short edges the growth stays close to the
// farthest a vertex really moves (sampled: a lower bound on it), where the chain's full length
// (each joint's lever as if the arm were stretched out) overstates it several times.
TEST(SceneChecker, IntervalGrowthFollowsThePose) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const SceneChecker scene(checker, std::make_shared<const Environment>(0.05));
  SceneCheckOptions moved_root;
  moved_root.root_pose = Transform{Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix(), Vec3(0.4, -1.2, 0.3)};
  const SceneChecker placed(checker, std::make_shared<const Environment>(0.05), moved_root);
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(0.0, 1.0), step(-0.3, 0.3);
  std::vector<double> ours, chain;  // sampled displacement / growth, per case and link
  for (int i = 0; i < 80; ++i) {  // (not reduced under the sanitizers: a median needs the cases)
    const std::vector<double> a = random_configuration(model, rng);
    std::vector<double> b = a;
    for (double& v : b) v += step(rng);
    const double lo = unit(rng), hi = lo + (1.0 - lo) * unit(rng), mid = 0.5 * (lo + hi);
    const std::vector<Transform> centre = poses_along(model, a, b, mid);
    std::vector<double> moved(model.links().size(), 0.0);
    for (int k = 0; k <= 20; ++k) {
      const std::vector<Transform> poses = poses_along(model, a, b, lo + (hi - lo) * k / 20.0);
      for (std::size_t l = 0; l < poses.size(); ++l) {
        for (const CollisionElement& e : model.links()[l].collision) {
          for (const Vec3& v : e.mesh->vertices) moved[l] = std::max(moved[l], (poses[l] * (e.origin * v) - centre[l] * (e.origin * v)).norm());
        }
      }
    }
    for (std::size_t l = 0; l < moved.size(); ++l) {
      if (moved[l] < 1e-6) continue;  // a link the motion does not move
      const double growth = scene.link_growth(static_cast<int>(l), a.data(), b.data(), lo, hi);
      ASSERT_LE(moved[l], growth) << model.links()[l].name << " case " << i;
      // Distances do not depend on where the robot stands: the same bound with its root moved.
      ASSERT_NEAR(placed.link_growth(static_cast<int>(l), a.data(), b.data(), lo, hi), growth, 1e-9 * (1.0 + growth));
      ours.push_back(moved[l] / growth);
      chain.push_back(moved[l] / (checker.link_speed(static_cast<int>(l), a.data(), b.data()) * 0.5 * (hi - lo)));
    }
  }
  auto median_of = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double median = median_of(ours), chain_median = median_of(chain);
  std::cout << ours.size() << " link intervals: sampled displacement / growth, median " << median << " (the chain's length: "
            << chain_median << ")\n";
  EXPECT_GT(median, 0.65);  // 0.77 on panda (its chain-length bound: 0.33)
  EXPECT_GT(median, 2.0 * chain_median);
}

// The links above `link`, itself first, up to the root.
std::vector<int> chain_of(const RobotModel& model, int link) {
  std::vector<int> out{link};
  for (bool moved = true; moved;) {
    moved = false;
    for (const RobotJoint& j : model.joints()) {
      if (j.child_link == out.back()) {
        out.push_back(j.parent_link);
        moved = true;
        break;
      }
    }
  }
  return out;
}

// The same for a self pair in the frame of the two links' deepest common ancestor, where the
// joints above it move neither: the largest displacement of a vertex of each link there, summed,
// bounds how far their distance can fall, and stays within the pair's growth, though only the
// joints between the two links count.
TEST(SceneChecker, PairGrowthHoldsEveryVertexInTheCommonAncestorsFrame) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const SceneChecker scene(checker, std::make_shared<const Environment>(0.05));
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double tightest = 0.0, saved = 0.0;
  for (int i = 0; i < test::sized(60); ++i) {
    const std::vector<double> a = random_configuration(model, rng), b = random_configuration(model, rng);
    const double lo = unit(rng), hi = lo + (1.0 - lo) * unit(rng);
    auto at = [&](double s) { return poses_along(model, a, b, s); };
    const std::vector<Transform> centre = at(0.5 * (lo + hi));
    std::vector<std::vector<Transform>> samples;
    for (int k = 0; k <= 10; ++k) samples.push_back(at(lo + (hi - lo) * k / 10.0));
    for (std::size_t p = 0; p < checker.checked_pairs().size(); ++p) {
      const auto [la, lb] = checker.checked_pairs()[p];
      const std::vector<int> up_a = chain_of(model, la), up_b = chain_of(model, lb);
      const int common = *std::find_if(up_a.begin(), up_a.end(), [&](int l) { return std::count(up_b.begin(), up_b.end(), l) > 0; });
      const double growth = scene.pair_growth(p, a.data(), b.data(), lo, hi);
      const double own = scene.link_growth(la, a.data(), b.data(), lo, hi) + scene.link_growth(lb, a.data(), b.data(), lo, hi);
      saved = std::max(saved, own / std::max(growth, 1e-12));
      for (const std::vector<Transform>& poses : samples) {
        double moved = 0.0;
        for (const int link : {la, lb}) {
          double farthest = 0.0;
          for (const CollisionElement& e : model.links()[link].collision) {
            for (const Vec3& v : e.mesh->vertices) {
              const Vec3 now = poses[common].inverse() * (poses[link] * (e.origin * v));
              const Vec3 then = centre[common].inverse() * (centre[link] * (e.origin * v));
              farthest = std::max(farthest, (now - then).norm());
            }
          }
          moved += farthest;
        }
        ASSERT_LE(moved, growth) << "pair " << p << " case " << i;
        if (growth > 0) tightest = std::max(tightest, moved / growth);
      }
    }
  }
  std::cout << "largest relative displacement / pair growth: " << tightest << "; the links' own growths sum to up to "
            << saved << " times as much\n";
  EXPECT_GT(tightest, 0.05);
  EXPECT_GT(saved, 2.0);  // the relative bound is much tighter for some pair
}

// Motions like a planner's edges between free states: free answers are free along a dense
// sweep (exact, every 2e-3 of the way); colliding answers collide where they say (at 1 cm:
// within 1 cm); at tolerance 0 the answers equal the checker's own certified check_motion.
TEST(SceneChecker, CertifiedMotionsHoldOnADenseSweep) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(13);
  std::size_t motions = 0, free_motions = 0, earliest = 0;
  double earliest_reach = 0.0;  // last valid / colliding fraction, summed
  std::size_t earliest_intervals = 0;
  for (int scene = 0; scene < 2; ++scene) {
    const auto env = std::make_shared<const Environment>(test::generate_scene(11, 10 + scene).environment());
    for (const double tolerance : {0.0, 0.01}) {
      SceneCheckOptions options;
      options.tolerance = tolerance;
      const SceneChecker fast(checker, env, options);
      std::vector<std::vector<double>> free;
      while (free.size() < 12) {
        const std::vector<double> q = random_configuration(checker.model(), rng);
        if (!exact_collides(checker, q.data(), *env)) free.push_back(q);
      }
      for (std::size_t i = 0; i + 1 < free.size(); ++i, ++motions) {
        std::vector<double> b = free[i];
        for (std::size_t j = 0; j < b.size(); ++j) b[j] += 0.4 * (free[i + 1][j] - free[i][j]);
        const MotionResult r = fast.check_motion(free[i].data(), b.data());
        ASSERT_TRUE(r.certified) << r.message;
        if (tolerance == 0.0) {
          MotionRequest request;
          EXPECT_EQ(checker.check_motion(free[i].data(), b.data(), *env, request).valid, r.valid) << "motion " << i;
        }
        auto state = [&](double s) {
          std::vector<double> q(b.size());
          for (std::size_t j = 0; j < q.size(); ++j) q[j] = free[i][j] + s * (b[j] - free[i][j]);
          return q;
        };
        if (r.valid) {
          ++free_motions;
          for (int k = 0; k <= 500; ++k) ASSERT_FALSE(exact_collides(checker, state(k / 500.0).data(), *env)) << "motion " << i << " at " << k;
        } else {
          const std::vector<double> q = state(r.colliding_fraction);
          EXPECT_LE(exact_clearance(checker, q.data(), *env), tolerance + 2e-5 + 1e-9) << "motion " << i;  // within twice min_clearance
          EXPECT_LE(r.last_valid_fraction, r.colliding_fraction);
          // Looking for the earliest collision (what a planner's last valid state needs): the same
          // answer, a collision where it says, and free all the way up to the last valid fraction.
          const MotionResult e = fast.check_motion(free[i].data(), b.data(), true);
          ASSERT_FALSE(e.valid);
          // (Exact booleans with the links padded by that much: a distance query this close to a
          // contact takes most of a second.)
          EXPECT_TRUE(exact_collides(padded(tolerance + 2e-5 + 1e-9), state(e.colliding_fraction).data(), *env)) << "motion " << i;
          EXPECT_LE(e.last_valid_fraction, e.colliding_fraction);
          EXPECT_GE(e.last_valid_fraction, e.colliding_fraction - 1e-3);
          earliest_intervals += e.states_checked;
          for (int k = 0; k <= 200; ++k) {
            ASSERT_FALSE(exact_collides(checker, state(e.last_valid_fraction * k / 200.0).data(), *env)) << "motion " << i;
          }
          earliest_reach += e.last_valid_fraction / std::max(e.colliding_fraction, 1e-12);
          ++earliest;
        }
      }
    }
  }
  std::cout << motions << " motions, " << free_motions << " free; the earliest collision's last valid fraction reaches "
            << earliest_reach / std::max<std::size_t>(earliest, 1) << " of the way to it on average, in "
            << earliest_intervals << " intervals for " << earliest << " motions\n";
  EXPECT_GT(earliest_reach / std::max<std::size_t>(earliest, 1), 0.5);
  EXPECT_GT(free_motions, 0u);
  EXPECT_LT(free_motions, motions);
}

// Panda's straight motion from its ready pose (the fingers half open): joint 1 turned by 0.02 rad,
// joint 4 to `joint4` when given; its ends and its state at fraction s.
struct ReadyMotion {
  std::vector<double> a, b;
  explicit ReadyMotion(const RobotModel& model, std::optional<double> joint4 = std::nullopt) : a(model.variable_count(), 0.02) {
    auto variable = [&](const std::string& joint) { return static_cast<std::size_t>(model.joints()[model.joint_index(joint)].variable); };
    const double ready[] = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
    for (int j = 0; j < 7; ++j) a[variable("panda_joint" + std::to_string(j + 1))] = ready[j];
    b = a;
    b[variable("panda_joint1")] += 0.02;
    if (joint4) b[variable("panda_joint4")] = *joint4;
  }
  std::vector<double> at(double s) const {
    std::vector<double> q(a.size());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + s * (b[j] - a[j]);
    return q;
  }
};

// Within one interval, a link that barely moves and lies just inside its growth of an obstacle
// frees a stretch around the midpoint by its exact distance (it cannot close that gap sooner).
// The stretch holds only for the components that were measured: here the hand swings through a
// thin bar inside it (a large joint 4 motion, far beyond any piece's growth), while link 1, turned
// a little by joint 1, grazes a box at the base. The collision with the bar must be found.
TEST(SceneChecker, AStretchFreedByOneLinkDoesNotFreeAFasterOne) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const ReadyMotion motion(model, -0.6);
  const std::vector<double>& a = motion.a;
  const std::vector<double>& b = motion.b;
  auto state = [&](double s) { return motion.at(s); };
  const int link1 = model.link_index("panda_link1"), hand = model.link_index("panda_hand");
  const auto empty = std::make_shared<const Environment>(Environment(0.05));
  const SceneChecker bare(checker, empty);
  const double slow = bare.link_growth(link1, a.data(), b.data(), 0.0, 1.0);
  const double fast = bare.link_growth(hand, a.data(), b.data(), 0.0, 1.0);
  // A 2 cm box beside link 1 at the midpoint, 0.6 of link 1's growth away from it.
  const std::vector<Transform> mid = poses_along(model, a, b, 0.5);
  auto box_at = [&](double t) {
    Environment world(0.05);
    world.add_object("base_box", ObjectShape::box({0.02, 0.02, 0.02}), Transform::Translation(mid[link1].t + Vec3(0.0, -t, -0.05)));
    return world;
  };
  auto distance_at = [&](const Environment& world, double s) {
    EnvironmentRequest request;
    request.distance = true;
    request.contacts = false;
    const EnvironmentResult r = checker.check_environment(state(s).data(), world, request);
    return std::make_pair(r.collision ? 0.0 : r.min_distance, r.closest_link);
  };
  double lo = 0.0, hi = 0.5;
  for (int i = 0; i < 60; ++i) {
    const double t = 0.5 * (lo + hi);
    (distance_at(box_at(t), 0.5).first < 0.9 * slow ? lo : hi) = t;
  }
  Environment world = box_at(hi);
  const auto [gap, nearest] = distance_at(world, 0.5);
  ASSERT_EQ(nearest, link1);
  ASSERT_GT(gap, 0.0);
  ASSERT_LT(gap, slow);     // link 1 fails its grown test: its exact distance frees a stretch
  ASSERT_GT(fast, 0.4);     // the hand's growth over the motion: far beyond any piece's
  const std::vector<Transform> late = poses_along(model, a, b, 0.76);
  world.add_object("bar", ObjectShape::box({0.01, 0.01, 0.01}), Transform::Translation(late[hand].t));
  const auto env = std::make_shared<const Environment>(world);
  int first = -1;
  for (int k = 0; k <= 1000 && first < 0; ++k) first = exact_collides(checker, state(k / 1000.0).data(), *env) ? k : -1;
  ASSERT_GT(first, 500);  // free at the midpoint, colliding inside the stretch link 1 frees
  ASSERT_LT(first / 1000.0, 0.5 + 0.5 * gap / slow);
  const SceneChecker scene(checker, env);
  const MotionResult r = scene.check_motion(a.data(), b.data());
  EXPECT_FALSE(r.valid);
  const MotionResult e = scene.check_motion(a.data(), b.data(), true);
  ASSERT_FALSE(e.valid);
  EXPECT_TRUE(exact_collides(padded(2e-5 + 1e-9), state(e.colliding_fraction).data(), *env)) << e.colliding_fraction;
  EXPECT_GE(e.last_valid_fraction, first / 1000.0 - 1e-3 - 1e-3);
  std::cout << "growth over the motion: link 1 " << slow << " m, the hand " << fast << " m; link 1 " << gap
            << " m from its box; the bar met from " << first / 1000.0 << ", found at " << r.colliding_fraction << "\n";
}

// The same for one link near two objects: link 1's exact distance to the box beside it frees a
// stretch for that box only; a second box, met by link 1 inside that stretch, must still be found,
// whichever of the two the object grid offers first. (Found by a search over small boxes around
// link 1: one free at the midpoint and met within the stretch.)
TEST(SceneChecker, AStretchFreedByOneObjectDoesNotFreeAnother) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const ReadyMotion motion(model);
  const std::vector<double>& a = motion.a;
  const std::vector<double>& b = motion.b;
  auto state = [&](double s) { return motion.at(s); };
  const int link1 = model.link_index("panda_link1");
  const auto empty = std::make_shared<const Environment>(Environment(0.05));
  const double slow = SceneChecker(checker, empty).link_growth(link1, a.data(), b.data(), 0.0, 1.0);
  const std::vector<Transform> mid = poses_along(model, a, b, 0.5);
  auto link1_distance = [&](const Environment& world, double s) {
    EnvironmentRequest request;
    request.distance = true;
    request.contacts = false;
    const EnvironmentResult r = checker.check_environment(state(s).data(), world, request);
    return r.collision ? 0.0 : r.min_distance;
  };
  // The first box 0.6 of link 1's growth from it at the midpoint, on one side.
  auto first_box = [&](Environment& world, double t) {
    world.add_object("side", ObjectShape::box({0.02, 0.02, 0.02}), Transform::Translation(mid[link1].t + Vec3(0.0, -t, -0.05)));
  };
  double lo = 0.0, hi = 0.5;
  for (int i = 0; i < 60; ++i) {
    const double t = 0.5 * (lo + hi);
    Environment world(0.05);
    first_box(world, t);
    (link1_distance(world, 0.5) < 0.6 * slow ? lo : hi) = t;
  }
  Environment side(0.05);
  first_box(side, hi);
  const double gap = link1_distance(side, 0.5);
  ASSERT_GT(gap, 0.0);
  ASSERT_LT(gap, slow);
  // A 4 mm box around link 1, free at the midpoint and met inside the stretch the first frees.
  auto add_second = [&](Environment& world, const Vec3& at) {
    world.add_object("bar", ObjectShape::box({0.004, 0.004, 0.004}), Transform::Translation(at));
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  for (const char* order : {"side box, bar", "bar, side box"}) {
    const bool side_first = order[0] == 's';
    std::optional<Vec3> found;
    for (int tries = 0; tries < 4000 && !found; ++tries) {
      const Vec3 at = mid[link1].t + Vec3(u(rng), u(rng), u(rng));
      Environment world(0.05);
      add_second(world, at);
      if (link1_distance(world, 0.5) <= 0.0 || link1_distance(world, 0.5) > 0.5 * gap) continue;
      for (int k = 1; k <= 40 && !found; ++k) {
        if (link1_distance(world, 0.5 + k / 40.0 * 0.45 * gap / slow) <= 0.0) found = at;
      }
    }
    ASSERT_TRUE(found.has_value()) << order;
    Environment world(0.05);
    if (side_first) first_box(world, hi);
    add_second(world, *found);
    if (!side_first) first_box(world, hi);
    const auto env = std::make_shared<const Environment>(world);
    const SceneChecker scene(checker, env);
    EXPECT_FALSE(scene.check_motion(a.data(), b.data()).valid) << order;
    const MotionResult e = scene.check_motion(a.data(), b.data(), true);
    ASSERT_FALSE(e.valid) << order;
    EXPECT_TRUE(exact_collides(padded(2e-5 + 1e-9), state(e.colliding_fraction).data(), *env)) << e.colliding_fraction;
    // Free all the way to the last valid state (a planner goes there).
    for (int k = 0; k <= 200; ++k) {
      ASSERT_FALSE(exact_collides(checker, state(e.last_valid_fraction * k / 200.0).data(), *env))
          << order << ": last valid " << e.last_valid_fraction;
    }
  }
}

// A motion that starts within the tolerance of an obstacle (a planner's goal a few millimetres
// from a shelf) must be answered as at tolerance 0: the tolerance may not take its first
// interval as colliding, or the planner could never leave the goal. (The ends' clearance was
// judged by the tolerant state check, whose "free" only means beyond the padding: motions
// leaving a goal 2.6 mm from an object were refused at 1 cm and found free at 0.)
TEST(SceneChecker, MotionsFromAStateWithinTheToleranceAnswerAsExact) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const auto env = std::make_shared<const Environment>(test::generate_scene(11, 3).environment());
  const SceneChecker exact(checker, env);
  SceneCheckOptions at_1cm;
  at_1cm.tolerance = 0.01;
  const SceneChecker coarse(checker, env, at_1cm);
  std::mt19937_64 rng(37);
  int near = 0, compared = 0, free = 0;
  while (near < 4) {
    // A free state moved towards a colliding one until it lies within 1 cm of the collision.
    std::vector<double> lo = random_configuration(checker.model(), rng), hi = random_configuration(checker.model(), rng);
    if (exact.collides(lo.data()) || !exact.collides(hi.data())) continue;
    double clearance = exact_clearance(checker, lo.data(), *env);
    for (int k = 0; k < 40 && clearance > 0.008; ++k) {
      std::vector<double> mid(lo.size());
      for (std::size_t j = 0; j < mid.size(); ++j) mid[j] = 0.5 * (lo[j] + hi[j]);
      if (exact.collides(mid.data())) {
        hi = mid;
      } else {
        lo = mid;
        clearance = exact_clearance(checker, lo.data(), *env);
      }
    }
    if (clearance > 0.008 || clearance < 0.001) continue;
    ++near;
    for (int i = 0; i < 30; ++i) {
      std::vector<double> b = random_configuration(checker.model(), rng);
      for (std::size_t j = 0; j < b.size(); ++j) b[j] = lo[j] + 0.03 * (b[j] - lo[j]);
      if (exact.collides(b.data())) continue;
      ++compared;
      const bool truth = exact.check_motion(lo.data(), b.data()).valid;
      free += truth;
      EXPECT_EQ(coarse.check_motion(lo.data(), b.data()).valid, truth) << "near state " << near << " motion " << i;
    }
  }
  std::cout << compared << " motions from 4 states 1 to 8 mm from a collision, " << free << " free\n";
  EXPECT_GT(free, 0);
}

// A proxy level coarser than half the tolerance leaves an interval's growth no room within the
// tolerance: such motions are settled by exact distances, not bisected down to min_clearance
// (they were: 36 ms a motion on panda with a 20 mm level at 10 mm).
TEST(SceneChecker, ALevelCoarserThanTheToleranceStillCertifiesQuickly) {
  CheckerOptions options;
  options.proxy_levels = {0.02};
  const CollisionChecker checker = test::demo_arm_checker(options);
  Environment world(0.05);
  world.add_object("box", ObjectShape::box({0.2, 0.2, 0.2}), Transform::Translation(Vec3(0.45, 0.0, 0.5)));
  const auto env = std::make_shared<const Environment>(world);
  SceneCheckOptions at_1cm;
  at_1cm.tolerance = 0.01;
  const SceneChecker scene(checker, env, at_1cm);
  std::mt19937_64 rng(31);
  int free = 0;
  std::size_t most = 0, total = 0, motions = 0;
  for (int i = 0; i < 40; ++i) {
    const std::vector<double> a = random_configuration(checker.model(), rng), b = random_configuration(checker.model(), rng);
    if (scene.collides(a.data()) || scene.collides(b.data())) continue;
    const MotionResult r = scene.check_motion(a.data(), b.data());
    ASSERT_TRUE(r.certified) << r.message;
    most = std::max(most, r.states_checked);
    total += r.states_checked, ++motions;
    free += r.valid;
  }
  std::cout << motions << " motions, " << total << " intervals, at most " << most << " for one\n";
  EXPECT_LT(total, 1500 * motions);  // 640 a motion here; bisected to min_clearance: 5,100
  EXPECT_GT(free, 0);
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
    for (const double r : {lo, hi, hi * (1 + 1e-12), lo * (1 - 1e-12)}) ASSERT_NO_FATAL_FAILURE(expect_offered(c, r));
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

}  // namespace
}  // namespace bvh_collision
