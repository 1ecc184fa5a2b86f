// Where a certified exact motion's self pairs take their exact distance (query/motion_calibration.h).
#include "bvh_collision/query/motion_calibration.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <memory>
#include <random>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"

namespace bvh_collision {
namespace {

constexpr double kClearlyFaster = 0.9;

struct SampleMotion {
  std::vector<double> start, goal;
};

// Motions between free states (self only) that take some intervals to certify: from a uniform
// state a fraction (5-50 %) of the way to another, as a planner's edges and its simplifier's
// shortcuts go, kept where the finest level's growth needs `hard_intervals` or more (a motion
// settled in a few intervals costs the same at every growth, and would only add noise; on pr2
// most random motions are). A fixed seed: the same sample at every build.
std::vector<SampleMotion> sample_motions(const CollisionChecker& checker, const std::shared_ptr<const Environment>& empty,
                                         const MotionCalibrationSizes& sizes) {
  SceneCheckOptions options;
  options.environment = false;
  options.pair_exact_growth = 0.0;  // the finest level's
  const SceneChecker scene(checker, empty, options);
  std::mt19937_64 rng(20261204);
  std::uniform_real_distribution<double> fraction(0.05, 0.5);
  std::vector<SampleMotion> out;
  for (std::size_t a = 0; a < sizes.attempts && out.size() < sizes.motions; ++a) {
    SampleMotion m{random_configuration(checker.model(), rng), random_configuration(checker.model(), rng)};
    const double f = fraction(rng);
    for (std::size_t v = 0; v < m.goal.size(); ++v) m.goal[v] = m.start[v] + f * (m.goal[v] - m.start[v]);
    if (scene.collides(m.start.data()) || scene.collides(m.goal.data())) continue;
    if (scene.check_motion(m.start.data(), m.goal.data(), false).states_checked < sizes.hard_intervals) continue;
    out.push_back(std::move(m));
  }
  return out;
}

// The fastest of `rounds` runs of the sample on a scene checker with this pair exact growth (a new
// one each round: a checker remembers the motions a thread asked it); the intervals into `intervals`.
double timed(const CollisionChecker& checker, const std::shared_ptr<const Environment>& empty, double growth,
             const std::vector<SampleMotion>& motions, std::size_t rounds, std::size_t& intervals) {
  SceneCheckOptions options;
  options.environment = false;
  options.pair_exact_growth = growth;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t r = 0; r < rounds; ++r) {
    const SceneChecker scene(checker, empty, options);
    intervals = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (const SampleMotion& m : motions) intervals += scene.check_motion(m.start.data(), m.goal.data(), false).states_checked;
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

}  // namespace

PairExactGrowthChoice choose_pair_exact_growth(const CollisionChecker& checker, const MotionCalibrationSizes& sizes) {
  PairExactGrowthChoice choice;
  for (const ProxyLevel& level : checker.accelerators().proxy_levels()) choice.candidates.push_back(level.level);
  if (choice.candidates.size() < 2 || checker.collision_model().checked_pairs().empty()) return choice;
  const auto empty = std::make_shared<const Environment>(0.05);
  const std::vector<SampleMotion> motions = sample_motions(checker, empty, sizes);
  choice.motions = motions.size();
  choice.growth = choice.candidates.front();
  if (motions.empty()) return choice;
  for (std::size_t c = 0; c < choice.candidates.size(); ++c) {
    std::size_t intervals = 0;
    choice.seconds.push_back(timed(checker, empty, choice.candidates[c], motions, sizes.rounds, intervals));
    if (c == 0) choice.intervals = intervals;
  }
  // The finest unless a coarser one is faster by a tenth: a sample that cannot tell them apart
  // (a timing's noise, a query beside it on the node) leaves the choice as it was before.
  std::size_t best = 0;
  for (std::size_t c = 1; c < choice.seconds.size(); ++c) {
    if (choice.seconds[c] < kClearlyFaster * choice.seconds[0] && choice.seconds[c] < choice.seconds[best]) best = c;
  }
  choice.growth = choice.candidates[best];
  return choice;
}

}  // namespace bvh_collision
