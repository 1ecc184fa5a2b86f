// A certified motion whose end is itself closer to a collision than min_clearance (query/
// scene_checker.h): the end is a valid state (touching is collision, 0.2 um is not), so a planner
// must be able to reach it and leave it. Such ends are found by conservative advancement
// (advancement_oracle.h), run along motions that collide until the first state within 5, 1 or 0.2
// um: every state before it is proven farther than that, so the motion from the start to it is free, and
// the checker must say so, both ways, exact and at 1 cm. The motions that leave such an end for
// elsewhere are held against the same advancement run from both ends towards the middle: one
// answered free must be proven free by it. One binary with test_scene_checker.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "advancement_oracle.h"
#include "bvh_collision/query/scene_checker.h"
#include "checker_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"
#include "scene_checker_fixtures.h"

namespace bvh_collision {
namespace {

using scene_test::exact_clearance;
using scene_test::exact_collides;
using scene_test::panda;

std::vector<double> along(const std::vector<double>& a, const std::vector<double>& b, double s) {
  std::vector<double> q(a.size());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = s >= 1.0 ? b[j] : a[j] + s * (b[j] - a[j]);
  return q;
}

std::vector<double> free_state(const CollisionChecker& checker, const Environment& env, std::mt19937_64& rng) {
  for (;;) {
    std::vector<double> q = random_configuration(checker.model(), rng);
    if (!exact_collides(checker, q.data(), env)) return q;
  }
}

// Is the motion free by advancement from both ends to its middle, stopping within `stop` of a
// collision? (An end close to a collision is left by steps that grow as the motion leaves it:
// from the far end alone the steps would shrink towards it without end.)
bool advancement_free_both_ways(const CollisionChecker& checker, const std::vector<double>& a, const std::vector<double>& b,
                                const Environment& env, double stop) {
  MotionRequest request;
  request.min_clearance = stop;
  request.max_states = 200000;
  const std::vector<double> mid = along(a, b, 0.5);
  return test::advancement_motion(checker, a.data(), mid.data(), env, request).valid &&
         test::advancement_motion(checker, b.data(), mid.data(), env, request).valid;
}

// A state a motion reaches within 5 um (or 1, or 0.2) of a collision, and the free state it came from.
struct NearEnd {
  std::vector<double> from, near, beyond;  // beyond: the motion's own goal, past the near state
  double clearance;
  bool self;  // the closest thing is a self pair (else the environment)
};

std::vector<NearEnd> near_ends(const CollisionChecker& checker, const Environment& env, std::mt19937_64& rng, int count) {
  std::vector<NearEnd> found;
  MotionRequest request;
  while (static_cast<int>(found.size()) < count) {
    // Advancement stops within 5, 1 or 0.2 um in turn.
    request.min_clearance = std::array<double, 3>{5e-6, 1e-6, 2e-7}[found.size() % 3];
    const std::vector<double> a = free_state(checker, env, rng);
    const std::vector<double> b = random_configuration(checker.model(), rng);
    const MotionResult r = test::advancement_motion(checker, a.data(), b.data(), env, request);
    if (r.valid || !r.certified || r.colliding_fraction <= 0.0) continue;
    const std::vector<double> q = along(a, b, r.colliding_fraction);
    const double gap = exact_clearance(checker, q.data(), env);
    // (Advancement's last step covers at most 0.99 of the gap it took: the gap left is 1 % of
    // one above 5 um at least. Below 0.1 um, rounding decides what can be proven.)
    if (!(gap > 1e-7 && gap <= request.min_clearance)) continue;
    SelfCollisionRequest self;
    self.distance = true;
    found.push_back({a, q, b, gap, checker.check_self(q.data(), self).min_distance <= gap});
  }
  return found;
}

TEST(SceneChecker, AMotionReachesAndLeavesAStateCloserThanMinClearance) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(29);
  int self_ends = 0, object_ends = 0;
  double smallest = 1.0;
  for (int scene = 0; scene < 2; ++scene) {
    // Panda alone (its self pairs), then among a generated scene's objects.
    const auto env = std::make_shared<const Environment>(scene == 0 ? Environment(0.05) : test::generate_scene(11, 20).environment());
    const std::vector<NearEnd> ends = near_ends(checker, *env, rng, test::sized(8));
    for (const double tolerance : {0.0, 0.01}) {
      SceneCheckOptions options;
      options.tolerance = tolerance;
      const SceneChecker fast(checker, env, options);
      for (std::size_t i = 0; i < ends.size(); ++i) {
        const NearEnd& e = ends[i];
        const MotionResult in = fast.check_motion(e.from.data(), e.near.data());
        const MotionResult out = fast.check_motion(e.near.data(), e.from.data());
        EXPECT_TRUE(in.valid && in.certified) << "into end " << i << " (" << e.clearance << " m), tolerance " << tolerance
                                              << ": stops at " << in.last_valid_fraction << " " << in.message;
        EXPECT_TRUE(out.valid && out.certified) << "out of end " << i << " (" << e.clearance << " m), tolerance " << tolerance
                                                << ": stops at " << out.last_valid_fraction << " " << out.message;
        // The earliest collision asked for (the ROS service's certified motion): free too.
        EXPECT_TRUE(fast.check_motion(e.near.data(), e.from.data(), true).valid) << "end " << i;
        if (tolerance == 0.0) (e.self ? self_ends : object_ends) += 1;
        smallest = std::min(smallest, e.clearance);
      }
    }
  }
  std::cout << self_ends << " ends closest to a self pair, " << object_ends << " to an object; the closest "
            << smallest << " m\n";
  EXPECT_GT(self_ends, 0);
  EXPECT_GT(object_ends, 0);
}

// From such an end to other free states, and on past it the way its motion was going: an answer
// free is proven free by advancement from both ends (stopping within an eighth of the nearer
// end's clearance: a certified motion keeps at least about a quarter of it, query/scene_checker.h).
TEST(SceneChecker, AMotionFromAStateCloserThanMinClearanceIsFreeOnlyWhereItIs) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(31);
  int free_answers = 0, colliding = 0;
  for (int scene = 0; scene < 2; ++scene) {
    const auto env = std::make_shared<const Environment>(scene == 0 ? Environment(0.05) : test::generate_scene(11, 21).environment());
    const std::vector<NearEnd> ends = near_ends(checker, *env, rng, test::sized(6));
    const SceneChecker fast(checker, env, SceneCheckOptions{});
    for (std::size_t i = 0; i < ends.size(); ++i) {
      const NearEnd& e = ends[i];
      std::vector<std::vector<double>> goals{e.beyond, along(e.from, e.beyond, 0.5), free_state(checker, *env, rng)};
      for (std::size_t g = 0; g < goals.size(); ++g) {
        const MotionResult r = fast.check_motion(e.near.data(), goals[g].data());
        ASSERT_TRUE(r.certified) << r.message;
        if (!r.valid) {
          ++colliding;
          continue;
        }
        ++free_answers;
        const double goal_clearance = exact_clearance(checker, goals[g].data(), *env);
        EXPECT_TRUE(advancement_free_both_ways(checker, e.near, goals[g], *env, std::min(e.clearance, goal_clearance) / 8.0))
            << "end " << i << " (" << e.clearance << " m), goal " << g;
      }
    }
  }
  std::cout << free_answers << " motions from such ends answered free, " << colliding << " colliding\n";
  EXPECT_GT(free_answers, 0);
  EXPECT_GT(colliding, 0);
}

}  // namespace
}  // namespace bvh_collision
