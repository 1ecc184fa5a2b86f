// What is built from a RobotCollisionModel to answer faster, held beside it (CollisionChecker
// keeps both): the proxy levels (narrowphase/link_proxy.h, each with its flat copy for the SIMD
// batch kernel) and the self pairs' clearance grids (model/pair_clearance.h). The model is what
// every query reads and what these are built from; it does not know them. Adding a proxy level
// copies these, not the model's meshes.
#pragma once

#include <atomic>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvh_collision/model/pair_clearance.h"
#include "bvh_collision/model/proxy_batch.h"
#include "bvh_collision/model/proxy_calibration.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/narrowphase/link_proxy.h"

namespace bvh_collision {

// One proxy level as built: its link proxies and what they cost.
struct ProxyLevel {
  double level = 0.0;
  std::vector<LinkProxy> links;  // per link (empty for links without geometry)
  std::size_t leaves = 0, memory_bytes = 0;
  std::size_t links_from_cache = 0;  // read from CheckerOptions::proxy_cache, not built
  std::size_t links_shared = 0;      // copies of an earlier link's whose shapes are the same (first_alike)
  double build_seconds = 0.0;  // the calibration included
  // Per checked pair, what the calibration measured (model/proxy_calibration.h; empty when
  // CheckerOptions::calibrate_proxies is off), and the pairs where the exact test was faster:
  // at a tolerance this level fits, those take the exact path, the others the proxies.
  std::vector<PairCost> pair_costs;
  std::vector<char> pair_exact;           // per checked pair
  std::vector<std::size_t> exact_pairs;   // the same, as indices
  bool answers(std::size_t pair) const { return pair >= pair_exact.size() || pair_exact[pair] == 0; }
  ProxyBatch batch;  // the pairs the proxies answer, flat, for the vectorised batch kernel
  // Whether batches take the SIMD lanes (then the exact pairs for the states found free): not
  // when the pairs left to the exact test carried most of the calibrated exact cost, where the
  // lanes would add their kinematics to a batch the exact test mostly answers anyway.
  bool lanes_pay = true;
  bool in_lanes() const { return lanes_pay && !batch.empty(); }
};

// RobotAccelerators::with_proxy_level stopped by its cancel flag.
struct ProxyBuildCancelled : std::runtime_error {
  ProxyBuildCancelled() : std::runtime_error("proxy level build cancelled") {}
};

class RobotAccelerators {
 public:
  RobotAccelerators() = default;
  // Built from `model`: the clearance grids (options.pair_clearance_cells), then the proxy levels
  // (options.proxy_levels, read from options.proxy_cache where it holds them). Throws
  // std::invalid_argument for a bad level.
  RobotAccelerators(const RobotCollisionModel& model, const CheckerOptions& options);

  // The proxy levels built, finest first; the coarsest level whose e is at most `tolerance`, or null.
  const std::vector<ProxyLevel>& proxy_levels() const { return proxy_levels_; }
  const ProxyLevel* proxies_for(double tolerance) const;
  const PairClearance& pair_clearance() const { return pair_clearance_; }
  // A certified exact motion's growth below which a self pair takes its exact distance rather
  // than a halved interval (SceneCheckOptions::pair_exact_growth; 0: the finest level's), chosen
  // by timing once the levels are built (query/motion_calibration.h): where a pair's distance
  // costs a few walks of its grown spheres (ur5e) it pays at a coarse level's growth, where it
  // costs a dozen or more (pr2's concave meshes) the finest level's spheres pay first.
  double pair_exact_growth() const { return pair_exact_growth_; }
  void set_pair_exact_growth(double growth) { pair_exact_growth_ = growth; }
  bool calibrates() const { return calibrate_; }  // CheckerOptions::calibrate_proxies

  // A copy with proxy level `level` built from `model` (the one these were built from) as well:
  // it answers every query as this one does and uses the level wherever it fits (a node builds
  // its levels this way after start-up, coarsest first, and swaps each copy in). `cancel`, once
  // true, stops the build between links with ProxyBuildCancelled. Throws std::invalid_argument
  // for a bad level.
  RobotAccelerators with_proxy_level(const RobotCollisionModel& model, double level,
                                     const std::atomic<bool>* cancel = nullptr) const;
  // A copy with the clearance grids of `cells` (read from the proxy cache when it holds them,
  // model/pair_clearance_cache.h; 0: none), the levels' batch plans made again (they note which
  // pairs have a grid): it answers every query as this one does. A node builds its grids so,
  // beside the queries, rather than at construction.
  RobotAccelerators with_pair_clearance(const RobotCollisionModel& model, std::size_t cells) const;
  // These for `carried` (RobotCollisionModel::carrying of the model these were built from): every
  // level gets the carried links' proxies (from the proxy cache when it holds them), the new self
  // pairs get no clearance grid. A carried object's proxies take what its size asks (a 30 cm box
  // 0.25 s at 5 mm, one core): with `proxies` false, no level at all (every
  // query takes the exact path, within the same contract) and nothing to build.
  RobotAccelerators carrying(const RobotCollisionModel& carried, bool proxies = true) const;

 private:
  ProxyLevel build_proxy_level(const RobotCollisionModel& model, double level, const std::atomic<bool>* cancel) const;
  void calibrate(const RobotCollisionModel& model, ProxyLevel& level, std::size_t first_pair) const;
  LinkProxy cached_or_built_proxy(const RobotCollisionModel& model, int link, double level, std::size_t& from_cache) const;

  std::string proxy_cache_;  // CheckerOptions::proxy_cache
  bool calibrate_ = true;    // CheckerOptions::calibrate_proxies
  std::vector<ProxyLevel> proxy_levels_;
  PairClearance pair_clearance_;
  double pair_exact_growth_ = 0.0;
};

}  // namespace bvh_collision
