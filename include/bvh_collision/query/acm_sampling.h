// Link pairs that random configurations show to collide never or always, as MoveIt's setup
// assistant finds them, with a cache file so that the sampling runs once per robot.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/query/collision_checker.h"

namespace bvh_collision {

struct SamplingOptions {
  std::size_t samples = 10000;
  double always_fraction = 0.95;  // "always": in collision in more than this share of samples
  std::uint64_t seed = 1;
};

struct SampledPairs {
  std::vector<std::pair<int, int>> never, always;  // link indices, a < b
  std::size_t samples = 0;
};

// Samples uniformly within joint limits (continuous joints over [-pi, pi]) and counts, for every
// pair the checker checks, the configurations in which it collides. Uses every core.
SampledPairs sample_collision_pairs(const CollisionChecker& checker, const SamplingOptions& options);

void apply_sampled_pairs(const SampledPairs& pairs, AllowedCollisionMatrix& acm);

// A key for the cache: a 64-bit FNV-1a hash of the URDF and SRDF text and the options, in hex.
std::string sampling_cache_key(const std::string& urdf_xml, const std::string& srdf_xml, const SamplingOptions& options);

// Reads pairs cached under `key` in `path` (false when absent, stale or unreadable: the caller
// samples again); writes them (false when the file cannot be written).
bool read_sampling_cache(const std::string& path, const std::string& key, const RobotModel& model, SampledPairs& out);
bool write_sampling_cache(const std::string& path, const std::string& key, const RobotModel& model, const SampledPairs& pairs);

}  // namespace bvh_collision
