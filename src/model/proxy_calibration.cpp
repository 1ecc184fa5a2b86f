// Where a proxy level pays, measured at build time (model/proxy_calibration.h).
#include "bvh_collision/model/proxy_calibration.h"

#include <algorithm>
#include <chrono>
#include <limits>
#include <random>

#include "bvh_collision/model/pair_clearance.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/narrowphase/compound_shape.h"
#include "bvh_collision/narrowphase/link_proxy.h"

namespace bvh_collision {
namespace {

// The sampled states' link poses, and per pair the states (indices) where a boolean self check
// would test it.
struct Samples {
  std::vector<std::vector<Transform>> poses;
  std::vector<std::vector<std::uint32_t>> near;  // per pair from first_pair
};

Samples sample_states(const RobotCollisionModel& model, const PairClearance& clearance, std::size_t first_pair,
                      const CalibrationSizes& sizes) {
  const auto& pairs = model.checked_pairs();
  Samples out;
  out.near.resize(pairs.size() - first_pair);
  std::mt19937_64 rng(20261204);  // fixed: the same states every build
  std::vector<Vec3> centers(model.bounds().size());
  for (std::size_t s = 0; s < sizes.states; ++s) {
    const std::vector<double> q = random_configuration(model.robot(), rng);
    std::vector<Transform> poses;
    model.kinematics().compute(q.data(), poses);
    for (std::size_t l = 0; l < centers.size(); ++l) {
      if (model.bounds()[l].radius >= 0) centers[l] = poses[l] * model.bounds()[l].center;
    }
    bool used = false;
    for (std::size_t p = first_pair; p < pairs.size(); ++p) {
      std::vector<std::uint32_t>& near = out.near[p - first_pair];
      if (near.size() >= sizes.per_pair) continue;
      const auto [a, b] = pairs[p];
      const double padding = model.paddings()[a] + model.paddings()[b];
      const double reach = model.bounds()[a].radius + model.bounds()[b].radius + padding;
      if ((centers[a] - centers[b]).squaredNorm() > reach * reach) continue;
      if (clearance.lower_bound(p, q.data()) > padding) continue;
      near.push_back(static_cast<std::uint32_t>(out.poses.size()));
      used = true;
    }
    if (used) out.poses.push_back(std::move(poses));
  }
  return out;
}

// The fastest of `rounds` runs of `test` over the samples, in seconds.
template <class Test>
double fastest(std::size_t rounds, const std::vector<std::uint32_t>& near, const Test& test) {
  double best = std::numeric_limits<double>::infinity();
  volatile bool sink = false;  // the answers are used, so no run is optimised away
  for (std::size_t r = 0; r < rounds; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    bool any = false;
    for (const std::uint32_t s : near) any = test(s) != any;
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    sink = any;
  }
  (void)sink;
  return best;
}

}  // namespace

std::vector<PairCost> measure_pair_costs(const RobotCollisionModel& model, const PairClearance& clearance,
                                         const std::vector<LinkProxy>& proxies, double level, std::size_t first_pair,
                                         const CalibrationSizes& sizes) {
  const auto& pairs = model.checked_pairs();
  std::vector<PairCost> out(pairs.size() - std::min(first_pair, pairs.size()));
  if (out.empty()) return out;
  const Samples samples = sample_states(model, clearance, first_pair, sizes);
  PairRequest request;
  request.tolerance = level;  // the exact path as it runs at the tolerances this level fits
  QueryStats stats;
  for (std::size_t i = 0; i < out.size(); ++i) {
    // (Named, not bound: clang 14's C++17 lets no lambda capture a structured binding.)
    const int a = pairs[first_pair + i].first, b = pairs[first_pair + i].second;
    const std::vector<std::uint32_t>& near = samples.near[i];
    out[i].samples = static_cast<std::uint32_t>(near.size());
    if (near.empty() || proxies[a].empty() || proxies[b].empty()) continue;
    request.padding = model.paddings()[a] + model.paddings()[b];
    const CompoundShape ca = model.compound(a), cb = model.compound(b);
    out[i].exact_seconds = fastest(sizes.rounds, near, [&](std::uint32_t s) {
      const std::vector<Transform>& poses = samples.poses[s];
      return compounds_collide(ca, poses[a], cb, poses[b], request, nullptr, stats);
    });
    out[i].proxy_seconds = fastest(sizes.rounds, near, [&](std::uint32_t s) {
      const std::vector<Transform>& poses = samples.poses[s];
      return proxies_overlap(proxies[a], poses[a], proxies[b], poses[b], request.padding);
    });
  }
  return out;
}

}  // namespace bvh_collision
