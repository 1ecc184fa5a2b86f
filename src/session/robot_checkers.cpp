// The session's checkers: proxy levels built beside the queries, carried objects, the prepared
// scene (session/robot_checkers.h).
#include "bvh_collision/session/robot_checkers.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace bvh_collision {

RobotCheckers::RobotCheckers(CollisionChecker robot, std::vector<double> levels, std::size_t sphere_budget, SessionLog log,
                             std::size_t grid_cells)
    : current_(std::make_shared<const CollisionChecker>(std::move(robot))),
      levels_(std::move(levels)),
      sphere_budget_(sphere_budget),
      log_(std::move(log)),
      grid_cells_(grid_cells) {
  if (!log_) log_ = [](SessionLogLevel, const std::string&) {};
}

RobotCheckers::~RobotCheckers() {
  stop_ = true;  // the build stops at its next link
  if (proxy_builder_.joinable()) proxy_builder_.join();
  {
    std::lock_guard<std::mutex> lock(carried_mutex_);  // (no new carried build starts after this)
    carried_.base = nullptr;
  }
  if (carried_builder_.joinable()) carried_builder_.join();
}

void RobotCheckers::start_proxy_levels() {
  if ((levels_.empty() && grid_cells_ == 0) || proxy_builder_.joinable()) return;
  proxy_builder_ = std::thread([this] { build_proxy_levels(); });
}

void RobotCheckers::wait_for_proxy_levels() {
  if (proxy_builder_.joinable()) proxy_builder_.join();
}

// The grids first (each level's batch plan notes which pairs have one), then the levels coarsest
// first: the cheapest level serves the widest range of tolerances soonest. Each is built into a
// copy of the checker, which then replaces the one queries take (a query in flight keeps the one
// it took).
void RobotCheckers::build_proxy_levels() {
  if (grid_cells_ > 0) build_pair_clearance();
  std::vector<double> levels = levels_;
  std::sort(levels.rbegin(), levels.rend());
  for (std::size_t i = 0; i < levels.size() && !stop_; ++i) {
    try {
      auto next = std::make_shared<const CollisionChecker>(current()->with_proxy_level(levels[i], &stop_));
      const ProxyLevel* built = next->accelerators().proxies_for(levels[i]);
      std::atomic_store(&current_, std::shared_ptr<const CollisionChecker>(next));
      char line[300];
      std::snprintf(line, sizeof line, "proxy level %.4g m ready: %zu spheres, %.1f KiB, in %.2f s (%zu links from the cache)",
                    built->level, built->leaves, built->memory_bytes / 1024.0, built->build_seconds, built->links_from_cache);
      if (const double growth = next->accelerators().pair_exact_growth(); growth > 0.0) {
        const std::size_t used = std::strlen(line);
        std::snprintf(line + used, sizeof line - used, "; exact motions' self pairs take their distance from %.4g m of growth (timed)", growth);
      }
      log_(SessionLogLevel::kInfo, line);
      // A surface's cover grows as the inverse square of the level: the next one's spheres are
      // predicted from this one's, and a level predicted beyond the budget is not built (pr2:
      // 28,346 at 20 mm predict 113k at 10 mm, built 105,893; those predict 424k at 5 mm, built
      // 415,194).
      if (i + 1 < levels.size()) {
        const double ratio = levels[i] / levels[i + 1];
        const auto predicted = static_cast<std::size_t>(std::llround(static_cast<double>(built->leaves) * ratio * ratio));
        if (predicted > sphere_budget_) {
          std::snprintf(line, sizeof line, "finer proxy levels skipped: %.4g m would need about %zu spheres (budget %zu)",
                        levels[i + 1], predicted, sphere_budget_);
          log_(SessionLogLevel::kInfo, line);
          return;
        }
      }
    } catch (const ProxyBuildCancelled&) {
      return;
    } catch (const std::exception& e) {
      log_(SessionLogLevel::kError, "proxy level " + std::to_string(levels[i]) + " m not built: " + e.what());
      return;
    }
  }
}

void RobotCheckers::build_pair_clearance() {
  try {
    auto next = std::make_shared<const CollisionChecker>(current()->with_pair_clearance(grid_cells_));
    const PairClearance& grids = next->accelerators().pair_clearance();
    std::atomic_store(&current_, std::shared_ptr<const CollisionChecker>(next));
    char line[200];
    std::snprintf(line, sizeof line, "clearance grids ready: %zu of %zu checked pairs, %.1f KiB, %s in %.2f s", grids.grids().size(),
                  next->collision_model().checked_pairs().size(), grids.memory_bytes() / 1024.0,
                  grids.from_cache() ? "read from the cache" : "built", grids.build_seconds());
    log_(SessionLogLevel::kInfo, line);
  } catch (const std::exception& e) {
    log_(SessionLogLevel::kError, std::string("clearance grids not built (the same answers go on without them): ") + e.what());
  }
}

std::shared_ptr<const CollisionChecker> RobotCheckers::for_snapshot(const std::shared_ptr<const Environment>& env) const {
  std::shared_ptr<const CollisionChecker> base = current();
  if (env->attached().empty()) return base;
  std::lock_guard<std::mutex> lock(carried_mutex_);
  const Carried key{base, env->attached_list(), env->allowed_collisions_shared(), nullptr};
  if (!carried_.same(key)) {
    // At once and exact; the levels follow (a query never waits for a proxy build).
    carried_ = key;
    carried_.checker = std::make_shared<const CollisionChecker>(base->carrying(*env, false));
    carried_.levels = base->accelerators().proxy_levels().empty();
  }
  if (!carried_.levels) build_carried_levels(env);
  return carried_.checker;
}

void RobotCheckers::build_carried_levels(const std::shared_ptr<const Environment>& env) const {
  if (carried_building_ || carried_.base == nullptr) return;
  if (carried_builder_.joinable()) carried_builder_.join();  // finished: it cleared carried_building_ last
  carried_building_ = true;
  carried_builder_ = std::thread([this, key = carried_, env] {
    try {
      auto full = std::make_shared<const CollisionChecker>(key.base->carrying(*env));
      std::lock_guard<std::mutex> lock(carried_mutex_);
      if (carried_.same(key)) carried_.checker = std::move(full), carried_.levels = true;  // else attached anew meanwhile
    } catch (const std::exception& e) {
      log_(SessionLogLevel::kWarning, std::string("carried objects' proxy levels not built (exact answers go on): ") + e.what());
    }
    carried_building_ = false;
  });
}

std::shared_ptr<const SceneChecker> RobotCheckers::prepared(const std::shared_ptr<const Environment>& env, bool self,
                                                            bool environment, const Transform& root, double tolerance) const {
  const std::shared_ptr<const CollisionChecker> now = for_snapshot(env);
  std::lock_guard<std::mutex> lock(scene_mutex_);
  const auto same = [&](const SceneChecker& s) {
    const SceneCheckOptions& o = s.options();
    // (The same accelerators too: a scene prepared before the grids or a level joined goes on
    // without them otherwise, as long as the snapshot stays.)
    return &s.environment() == env.get() && &s.checker().collision_model() == &now->collision_model() &&
           &s.checker().accelerators() == &now->accelerators() && o.self == self &&
           o.environment == environment && o.root_pose.R == root.R && o.root_pose.t == root.t && o.tolerance == tolerance;
  };
  if (!scene_ || !same(*scene_)) {
    SceneCheckOptions options;
    options.self = self;
    options.environment = environment;
    options.tolerance = tolerance;
    options.root_pose = root;
    scene_ = std::make_shared<const SceneChecker>(*now, env, options);
  }
  return scene_;
}

}  // namespace bvh_collision
