// The self pairs' exact growth of certified motions (query/motion_calibration.h): every growth
// answers as every other and as conservative advancement (advancement_oracle.h, another
// algorithm) while the work differs; the choice is one of the levels, made on a bounded sample,
// kept by the checker and made again when a level is added. One binary with test_scene_checker.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "bvh_collision/query/motion_calibration.h"
#include "bvh_collision/query/scene_checker.h"
#include "advancement_oracle.h"
#include "checker_fixtures.h"
#include "robot_data.h"
#include "scene_checker_fixtures.h"

namespace bvh_collision {
namespace {

CollisionChecker with_levels(const std::string& robot) {
  if (robot == "panda") return scene_test::panda();
  CheckerOptions options;
  options.proxy_levels = {0.005, 0.01, 0.02};
  options.proxy_cache = test::proxy_cache_dir();
  return test::load_as_moveit(robot, options);
}

// Self motions from free states, some of them colliding, on the robot alone and beside a table:
// the same answer at each level's growth and advancement's, in fewer or more intervals.
TEST(PairExactGrowth, EveryGrowthAnswersAsAdvancement) {
  // (Under the sanitizers panda only: loading ur5e is most of the time there.)
  for (const std::string& robot : test::sanitized() ? std::vector<std::string>{"panda"} : std::vector<std::string>{"panda", "ur5e"}) {
    SCOPED_TRACE(robot);
    const CollisionChecker checker = with_levels(robot);
    std::vector<double> growths;
    for (const ProxyLevel& level : checker.accelerators().proxy_levels()) growths.push_back(level.level);
    ASSERT_EQ(growths.size(), 3u);
    Environment table(0.05);
    table.add_object("table", ObjectShape::box({1.2, 1.2, 0.04}), Transform::Translation({0.0, 0.0, -0.05}));
    std::mt19937_64 rng(57);
    std::uniform_real_distribution<double> fraction(0.2, 1.0);
    const int wanted = test::sized(16);
    int compared = 0, colliding = 0;
    std::vector<std::size_t> intervals(growths.size(), 0);
    for (int i = 0; i < 600 && (compared < wanted || colliding < 2 || compared - colliding < 2); ++i) {
      const auto env = std::make_shared<const Environment>(i % 2 == 0 ? Environment(0.05) : table);
      const std::vector<double> a = random_configuration(checker.model(), rng), r = random_configuration(checker.model(), rng);
      std::vector<double> b = a;
      const double f = fraction(rng);
      for (std::size_t v = 0; v < b.size(); ++v) b[v] += f * (r[v] - a[v]);
      if (scene_test::exact_collides(checker, a.data(), *env)) continue;
      const bool oracle = test::advancement_motion(checker, a.data(), b.data(), *env).valid;
      for (std::size_t g = 0; g < growths.size(); ++g) {
        SceneCheckOptions options;
        options.pair_exact_growth = growths[g];
        const MotionResult got = SceneChecker(checker, env, options).check_motion(a.data(), b.data(), false);
        ASSERT_TRUE(got.certified) << "motion " << i << " at " << growths[g];
        EXPECT_EQ(got.valid, oracle) << "motion " << i << " at " << growths[g];
        intervals[g] += got.states_checked;
      }
      ++compared;
      colliding += !oracle;
    }
    EXPECT_GE(compared, wanted);
    EXPECT_GE(colliding, 2);
    EXPECT_GE(compared - colliding, 2);
    // The growth changes the work (else this shows nothing): a coarser one takes exact distances
    // sooner and halves fewer intervals.
    EXPECT_LT(intervals.back(), intervals.front()) << intervals.front() << " intervals at the finest level's growth";
  }
}

TEST(PairExactGrowth, IsChosenAmongTheLevelsOnABoundedSample) {
  const CollisionChecker& panda = scene_test::panda();
  const double kept = panda.accelerators().pair_exact_growth();
  EXPECT_TRUE(kept == 0.005 || kept == 0.01 || kept == 0.02) << kept;
  MotionCalibrationSizes small;
  small.motions = 8;
  small.rounds = 1;
  const PairExactGrowthChoice choice = choose_pair_exact_growth(panda, small);
  EXPECT_EQ(choice.candidates, (std::vector<double>{0.005, 0.01, 0.02}));
  EXPECT_EQ(choice.motions, 8u);
  EXPECT_GT(choice.intervals, choice.motions);
  ASSERT_EQ(choice.seconds.size(), 3u);
  EXPECT_NE(std::find(choice.candidates.begin(), choice.candidates.end(), choice.growth), choice.candidates.end());
  // One level: nothing to choose, nothing timed.
  CheckerOptions one;
  one.proxy_levels = {0.02};
  one.proxy_cache = test::proxy_cache_dir();
  const CollisionChecker coarse = test::panda_as_moveit(one);
  EXPECT_EQ(coarse.accelerators().pair_exact_growth(), 0.0);
  const PairExactGrowthChoice none = choose_pair_exact_growth(coarse);
  EXPECT_EQ(none.motions, 0u);
  EXPECT_TRUE(none.seconds.empty());
  // A level added: chosen again, among both.
  const double again = coarse.with_proxy_level(0.01).accelerators().pair_exact_growth();
  EXPECT_TRUE(again == 0.01 || again == 0.02) << again;
  // Without calibration: the finest level's, as before the choice.
  CheckerOptions plain;
  plain.proxy_levels = {0.01, 0.02};
  plain.proxy_cache = test::proxy_cache_dir();
  plain.calibrate_proxies = false;
  EXPECT_EQ(test::panda_as_moveit(plain).accelerators().pair_exact_growth(), 0.0);
}

}  // namespace
}  // namespace bvh_collision
