// Where a certified exact motion's self pairs take their exact distance, measured when the proxy
// levels are built (as model/proxy_calibration.h measures where a level answers a pair).
//
// An interval whose grown proxies meet is either halved (two walks of a finer level, each with its
// midpoint checked) or settled at once by the pair's exact distance at its midpoint, which frees
// the stretch the pair cannot close. Which costs less depends on the robot's meshes, and no rule
// from counts told it: on uniform states near contact ur5e's pairs take a distance in the time of
// 2-7 walks of their grown spheres, pr2's in that of 12-23 (concave meshes, a BVH walk each). ur5e
// plans faster when its pairs take the distance as soon as the coarsest level fails (the exact
// rows' plan time 0.81-0.85 of the finest level's), pr2 slower (1.13 at 10 mm, 1.40 at 20 mm). So
// each level's growth is timed on one fixed sample of certified self motions and the fastest
// kept, the finest unless another is clearly faster. The answers are the same whichever is
// chosen: only the work differs (test_motion_calibration.cpp checks it against advancement).
#pragma once

#include <cstddef>
#include <vector>

namespace bvh_collision {

class CollisionChecker;

struct MotionCalibrationSizes {
  std::size_t motions = 64;        // motions from a fixed seed, between free states
  std::size_t rounds = 3;          // each candidate timed this many times; the fastest round counts
  std::size_t attempts = 2000;     // random motions tried, at most
  std::size_t hard_intervals = 8;  // a motion is kept when it needs this many intervals or more
};

struct PairExactGrowthChoice {
  double growth = 0.0;                // the chosen growth (m), one of the levels; 0 without two levels
  std::vector<double> candidates;     // the levels, finest first
  std::vector<double> seconds;        // per candidate: the sample's fastest round
  std::size_t motions = 0;            // motions in the sample
  std::size_t intervals = 0;          // their intervals at the finest level's growth (a count of the work)
};

// Times `checker`'s certified exact self motions (no environment) with each of its proxy levels
// as the pairs' exact growth, and returns the fastest; a coarser level must be faster by a tenth
// to replace the finest (the choice before this calibration). Without two levels: growth 0, no motion.
PairExactGrowthChoice choose_pair_exact_growth(const CollisionChecker& checker, const MotionCalibrationSizes& sizes = {});

}  // namespace bvh_collision
