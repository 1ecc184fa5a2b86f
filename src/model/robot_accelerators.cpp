// The accelerators built from a RobotCollisionModel (model/robot_accelerators.h).
#include "bvh_collision/model/robot_accelerators.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

#include "bvh_collision/model/pair_clearance_cache.h"
#include "bvh_collision/narrowphase/link_proxy_cache.h"

namespace bvh_collision {

RobotAccelerators::RobotAccelerators(const RobotCollisionModel& model, const CheckerOptions& options)
    : proxy_cache_(options.proxy_cache), calibrate_(options.calibrate_proxies) {
  if (options.pair_clearance_cells > 0) {
    pair_clearance_ = cached_or_built_pair_clearance(model, options.pair_clearance_cells, options.proxy_cache);
  }
  // After the grids: the batch plans note which pairs have one.
  std::vector<double> levels = options.proxy_levels;
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  for (const double level : levels) proxy_levels_.push_back(build_proxy_level(model, level, nullptr));
}

ProxyLevel RobotAccelerators::build_proxy_level(const RobotCollisionModel& model, double level,
                                                const std::atomic<bool>* cancel) const {
  if (!(level > 0.0) || !std::isfinite(level)) {
    throw std::invalid_argument("proxy level " + std::to_string(level) + " m: must be a positive number of metres");
  }
  const auto start = std::chrono::steady_clock::now();
  ProxyLevel out;
  out.level = level;
  out.links.resize(model.shapes().size());
  // A link whose shapes are an earlier link's (a robot's two arms, its casters) takes that proxy.
  std::vector<std::vector<BodyShape>> placed(model.shapes().size());
  for (std::size_t l = 0; l < placed.size(); ++l) {
    if (!model.shapes()[l].empty()) placed[l] = model.placed_shapes(static_cast<int>(l));
  }
  const std::vector<std::size_t> alike = first_alike(placed);
  for (std::size_t l = 0; l < model.shapes().size(); ++l) {
    if (model.shapes()[l].empty()) continue;
    if (cancel != nullptr && cancel->load()) throw ProxyBuildCancelled();
    if (alike[l] != l) {
      out.links[l] = out.links[alike[l]];
      ++out.links_shared;
    } else {
      out.links[l] = cached_or_built_proxy(model, static_cast<int>(l), level, out.links_from_cache);
    }
    out.leaves += out.links[l].leaf_count();
    out.memory_bytes += out.links[l].memory_bytes();
  }
  calibrate(model, out, 0);
  out.batch = ProxyBatch(model, pair_clearance_, out);
  out.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

// The pairs from `first_pair` on timed both ways (model/proxy_calibration.h); where the exact
// test was faster, the level leaves the pair to it.
void RobotAccelerators::calibrate(const RobotCollisionModel& model, ProxyLevel& level, std::size_t first_pair) const {
  const std::size_t pairs = model.checked_pairs().size();
  level.pair_costs.resize(std::min(first_pair, level.pair_costs.size()));
  level.pair_exact.resize(pairs, 0);
  if (calibrate_) {
    const std::vector<PairCost> costs = measure_pair_costs(model, pair_clearance_, level.links, level.level, first_pair);
    level.pair_costs.insert(level.pair_costs.end(), costs.begin(), costs.end());
    for (std::size_t p = first_pair; p < pairs; ++p) level.pair_exact[p] = costs[p - first_pair].proxies_pay() ? 0 : 1;
  }
  level.exact_pairs.clear();
  double proxied = 0.0, left = 0.0;  // the calibrated exact cost of the pairs either way
  for (std::size_t p = 0; p < pairs; ++p) {
    if (level.pair_exact[p]) level.exact_pairs.push_back(p);
    if (p < level.pair_costs.size()) (level.pair_exact[p] ? left : proxied) += level.pair_costs[p].exact_seconds;
  }
  level.lanes_pay = proxied >= left;
}

// From the cache when it holds this link's proxy at this level (its key covers every number of
// the link's shapes), else built and stored there.
LinkProxy RobotAccelerators::cached_or_built_proxy(const RobotCollisionModel& model, int link, double level,
                                                   std::size_t& from_cache) const {
  const std::vector<BodyShape> shapes = model.placed_shapes(link);
  if (proxy_cache_.empty()) return LinkProxy::build(shapes, level);
  const std::uint64_t key = link_proxy_key(shapes, level);
  if (std::optional<LinkProxy> cached = read_cached_link_proxy(proxy_cache_, key)) {
    ++from_cache;
    return std::move(*cached);
  }
  LinkProxy built = LinkProxy::build(shapes, level);
  write_cached_link_proxy(proxy_cache_, key, built);  // a cache that cannot be written only costs time
  return built;
}

RobotAccelerators RobotAccelerators::with_proxy_level(const RobotCollisionModel& model, double level,
                                                      const std::atomic<bool>* cancel) const {
  ProxyLevel built = build_proxy_level(model, level, cancel);
  RobotAccelerators copy = *this;
  auto& levels = copy.proxy_levels_;
  const auto at = std::find_if(levels.begin(), levels.end(), [&](const ProxyLevel& p) { return p.level >= level; });
  if (at != levels.end() && at->level == level) {
    *at = std::move(built);
  } else {
    levels.insert(at, std::move(built));
  }
  return copy;
}

RobotAccelerators RobotAccelerators::with_pair_clearance(const RobotCollisionModel& model, std::size_t cells) const {
  RobotAccelerators copy = *this;
  copy.pair_clearance_ = cells > 0 ? cached_or_built_pair_clearance(model, cells, proxy_cache_) : PairClearance();
  for (ProxyLevel& level : copy.proxy_levels_) level.batch = ProxyBatch(model, copy.pair_clearance_, level);
  return copy;
}

RobotAccelerators RobotAccelerators::carrying(const RobotCollisionModel& carried, bool proxies) const {
  RobotAccelerators copy = *this;
  copy.pair_clearance_ = pair_clearance_.for_pairs(carried.checked_pairs().size());
  if (!proxies) copy.proxy_levels_.clear();
  for (ProxyLevel& level : copy.proxy_levels_) {
    const std::size_t before = level.links.size();
    level.links.resize(carried.shapes().size());
    for (std::size_t l = before; l < carried.shapes().size(); ++l) {
      if (carried.shapes()[l].empty()) continue;
      level.links[l] = copy.cached_or_built_proxy(carried, static_cast<int>(l), level.level, level.links_from_cache);
      level.leaves += level.links[l].leaf_count();
      level.memory_bytes += level.links[l].memory_bytes();
    }
    copy.calibrate(carried, level, level.pair_exact.size());  // the carried bodies' new pairs
    level.batch = ProxyBatch(carried, copy.pair_clearance_, level);
  }
  return copy;
}

const ProxyLevel* RobotAccelerators::proxies_for(double tolerance) const {
  const ProxyLevel* best = nullptr;
  for (const ProxyLevel& p : proxy_levels_) {
    if (p.level <= tolerance) best = &p;
  }
  return best;
}

}  // namespace bvh_collision
