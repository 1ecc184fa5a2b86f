// SceneChecker's certified motions at a tolerance (query/scene_checker.h): a motion may count as
// colliding where it comes within the tolerance of a collision, never from or to a state within it
// (a planner must leave its goal), and a motion that grazes an object within the tolerance is
// settled there, not bisected down to its gap; a level coarser than the tolerance still certifies
// quickly. Held to exact distances and booleans of the checker's general queries. One binary with
// test_scene_checker.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include "bvh_collision/query/scene_checker.h"
#include "checker_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"
#include "scene_checker_fixtures.h"

namespace bvh_collision {
namespace {

using scene_test::exact_clearance;
using scene_test::panda;

// A motion that starts within the tolerance of an obstacle (a planner's goal a few millimetres
// from a shelf) must be answered as at tolerance 0: the tolerance may not take its first
// interval as colliding, or the planner could never leave the goal. (The ends' clearance was
// judged by the tolerant state check, whose "free" only means beyond the padding: motions
// leaving a goal 2.6 mm from an object were refused at 1 cm and found free at 0.) The same towards it.
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
      std::vector<double> b = random_configuration(checker.model(), rng), c = random_configuration(checker.model(), rng);
      for (std::size_t j = 0; j < b.size(); ++j) b[j] = lo[j] + 0.03 * (b[j] - lo[j]), c[j] = lo[j] + 0.03 * (c[j] - lo[j]);
      if (exact.collides(b.data()) || exact.collides(c.data())) continue;
      ++compared;
      const bool truth = exact.check_motion(lo.data(), b.data()).valid, back = exact.check_motion(c.data(), lo.data()).valid;
      free += truth;
      EXPECT_EQ(coarse.check_motion(lo.data(), b.data()).valid, truth) << "near state " << near << " motion " << i;
      // Towards it from elsewhere, known free (checked first, as a planner does): the goal is posed
      // only when the tolerance asks, and must then be its own poses, not the last goal's (b).
      EXPECT_FALSE(coarse.collides(lo.data()));
      EXPECT_EQ(coarse.check_motion(c.data(), lo.data()).valid, back) << "to near state " << near << " motion " << i;
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


// Motions among generated scenes of a planner's kind (each joint a sixth of the way to a random
// state) that pass within 8 mm of a collision but not within 1 mm (exact at tolerance 0 with the
// links padded by so much, no proxies), and are farther than 16 mm from everything at both ends.
// At 1 cm a failing interval whose proxies (the 1 cm level: 5 mm from an obstacle) met an object,
// grown by at most 5 mm less the margins, came within the tolerance at its midpoint: the motion
// counts as colliding there, where it used to be bisected until the growth fell below the proxies'
// gap to the object. Every colliding answer is within the tolerance of a collision where it says
// (the checker's exact distances, another code path); every free one was found free at tolerance 0.
TEST(SceneChecker, AMotionGrazingAnObjectIsSettledWithinTheTolerance) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  CheckerOptions padded_options;
  padded_options.padding = 0.008;  // (a self pair then by twice that)
  const CollisionChecker padded8 = test::panda_as_moveit(padded_options);
  padded_options.padding = 0.001;
  const CollisionChecker padded1 = test::panda_as_moveit(padded_options);
  std::mt19937_64 rng(41);
  std::size_t grazing = 0, intervals = 0, colliding = 0;
  for (int scene = 0; scene < 4; ++scene) {
    const auto env = std::make_shared<const Environment>(test::generate_scene(11, 20 + scene).environment());
    SceneCheckOptions at_1cm;
    at_1cm.tolerance = 0.01;
    const SceneChecker exact(checker, env), coarse(checker, env, at_1cm), within8(padded8, env), within1(padded1, env);
    for (int attempt = 0, found = 0; attempt < 2000 && found < 6; ++attempt) {
      const std::vector<double> a = random_configuration(checker.model(), rng);
      std::vector<double> b = random_configuration(checker.model(), rng);
      for (std::size_t j = 0; j < b.size(); ++j) b[j] = a[j] + (b[j] - a[j]) / 6.0;
      if (within8.collides(a.data()) || within8.collides(b.data()) || !exact.check_motion(a.data(), b.data()).valid ||
          within8.check_motion(a.data(), b.data()).valid || !within1.check_motion(a.data(), b.data()).valid) {
        continue;
      }
      if (exact_clearance(checker, a.data(), *env) < 0.016 || exact_clearance(checker, b.data(), *env) < 0.016) continue;
      ++grazing, ++found;
      const MotionResult r = coarse.check_motion(a.data(), b.data());
      ASSERT_TRUE(r.certified) << r.message;
      intervals += r.states_checked;
      if (r.valid) continue;
      ++colliding;
      std::vector<double> at(a.size());
      for (std::size_t j = 0; j < at.size(); ++j) at[j] = a[j] + r.colliding_fraction * (b[j] - a[j]);
      EXPECT_LE(exact_clearance(checker, at.data(), *env), at_1cm.tolerance + 2.0 * at_1cm.min_clearance + 1e-9) << "scene " << scene;
    }
  }
  std::cout << grazing << " motions passing 1-8 mm from a collision: " << colliding << " colliding at 1 cm, " << intervals
            << " intervals\n";
  EXPECT_GE(grazing, 16u);
  EXPECT_LT(intervals, 32 * grazing);  // 26.6 a motion here; bisected to the proxies' gap: 37.7
}

}  // namespace
}  // namespace bvh_collision
