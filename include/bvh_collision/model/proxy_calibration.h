// Where a proxy level pays, measured at build time (docs/design.md: a tolerance buys speed or
// costs nothing). A level's proxies may answer a self pair alone at a tolerance that fits them
// (narrowphase/tolerance_policy.h), but whether they answer it faster than the exact test depends
// on the pair: a box link's 12 triangles are tested faster than its hundreds of 2 mm spheres, a
// 2,000-triangle mesh slower than its 20 mm spheres. No rule from counts told it (a box link is a
// 12-triangle mesh like any other; panda's 5 mm level has more leaves than triangles and pays), so
// each pair is timed both ways on the states of a fixed sample where it passes the broad phase,
// and the proxies answer it only where they were not slower. Either way the answer keeps the
// contract: the exact test is exact, the proxies are within their level.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace bvh_collision {

class LinkProxy;
class PairClearance;
class RobotCollisionModel;

// One checked pair's measured costs: the exact test (the narrowphase at tolerance = level,
// boolean, solids) and the proxies' overlap test, each summed over the same sampled states (the
// fastest of several rounds, so a preemption does not decide).
struct PairCost {
  std::uint32_t samples = 0;  // sampled states where the pair passed the broad phase
  double exact_seconds = 0.0, proxy_seconds = 0.0;
  // Proxies answer unless measured slower; a pair no sampled state brought near keeps them.
  bool proxies_pay() const { return samples == 0 || proxy_seconds <= exact_seconds; }
};

// How many states the calibration samples and how many it times per pair.
struct CalibrationSizes {
  std::size_t states = 512;     // uniform random states within joint limits (a fixed seed)
  std::size_t per_pair = 24;    // at most this many of them timed per pair
  std::size_t rounds = 5;       // each timed this many times; the fastest round counts
};

// The costs of the checked pairs [first_pair, end) with `proxies` (one per link, empty for links
// without geometry) at `level`: the pairs a boolean self check would test (the bounding spheres
// within reach, no clearance grid clearing the padding).
std::vector<PairCost> measure_pair_costs(const RobotCollisionModel& model, const PairClearance& clearance,
                                         const std::vector<LinkProxy>& proxies, double level, std::size_t first_pair = 0,
                                         const CalibrationSizes& sizes = {});

}  // namespace bvh_collision
