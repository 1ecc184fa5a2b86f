// The checkers a running node answers with, without ROS: the robot's own, to which its clearance
// grids and then its proxy levels join as a thread of their own builds them (the grids first, read
// from the proxy cache when it holds them; the levels coarsest first, each put to use when done;
// until then the same answers come by the exact paths, within the same contract); the one carrying a
// snapshot's attached objects, built once per attachment (exact at once, its levels built beside
// the queries); and the prepared scene certified motions go through, kept while the snapshot and
// the request's checks stay the same.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"

namespace bvh_collision {

// Where a session's messages go (the node: its log; a test: a vector).
enum class SessionLogLevel { kInfo, kWarning, kError };
using SessionLog = std::function<void(SessionLogLevel, const std::string&)>;

class RobotCheckers {
 public:
  // `levels` (m): the proxy levels to build, any order, coarsest first; a finer level predicted
  // (from the one before) to need more than `sphere_budget` spheres is not built, nor any after it.
  // `grid_cells` > 0: the clearance grids to build before them (CheckerOptions::pair_clearance_cells;
  // `robot` then has none, so that no start waits on them: pr2 without an SRDF, 3-6 s on one core).
  RobotCheckers(CollisionChecker robot, std::vector<double> levels, std::size_t sphere_budget, SessionLog log,
                std::size_t grid_cells = 0);
  ~RobotCheckers();  // stops the builds (at their next link, or once the grids are built) and waits for them
  RobotCheckers(const RobotCheckers&) = delete;
  RobotCheckers& operator=(const RobotCheckers&) = delete;

  // Starts building the clearance grids and the proxy levels (once; nothing when there are none).
  void start_proxy_levels();
  // Waits for their build to end (tests; a node never waits).
  void wait_for_proxy_levels();

  // The robot's checker now. Hold the pointer while using references into it.
  std::shared_ptr<const CollisionChecker> current() const { return std::atomic_load(&current_); }
  // The checker a query on snapshot `env` uses: current() carrying env's attached objects, built
  // once per attachment and kept; current() itself when nothing is attached. A new attachment is
  // carried at once without proxy levels (exact answers), and a thread builds the checker with
  // them and swaps it in (a large object's take seconds).
  std::shared_ptr<const CollisionChecker> for_snapshot(const std::shared_ptr<const Environment>& env) const;
  // Does the kept checker for env's attached objects have its proxy levels yet?
  bool carried_levels_built(const Environment& env) const {
    std::lock_guard<std::mutex> lock(carried_mutex_);
    return carried_.attached == env.attached_list() && carried_.levels;
  }
  // The prepared scene certified motions on `env` go through for these checks, root pose and
  // tolerance: the one kept since the last call when none changed.
  std::shared_ptr<const SceneChecker> prepared(const std::shared_ptr<const Environment>& env, bool self, bool environment,
                                               const Transform& root, double tolerance) const;

 private:
  void build_proxy_levels();
  void build_pair_clearance();
  void build_carried_levels(const std::shared_ptr<const Environment>& env) const;  // carried_mutex_ held

  std::shared_ptr<const CollisionChecker> current_;  // read and replaced atomically
  std::vector<double> levels_;
  std::size_t sphere_budget_;
  SessionLog log_;
  std::size_t grid_cells_;
  std::thread proxy_builder_;
  std::atomic<bool> stop_{false};

  mutable std::mutex scene_mutex_;
  mutable std::shared_ptr<const SceneChecker> scene_;
  // The last for_snapshot(): the checker it carried the attached objects on, the snapshot's list
  // and allowed collisions it was built for (held, so that their addresses stay theirs), and it.
  struct Carried {
    std::shared_ptr<const CollisionChecker> base;
    std::shared_ptr<const std::vector<AttachedBody>> attached;
    std::shared_ptr<const NamedAllowedCollisions> allowed;
    std::shared_ptr<const CollisionChecker> checker;
    bool levels = false;  // `checker` has base's proxy levels (else none yet)
    bool same(const Carried& o) const { return base == o.base && attached == o.attached && allowed == o.allowed; }
  };
  mutable std::mutex carried_mutex_;
  mutable Carried carried_;
  mutable std::thread carried_builder_;
  mutable std::atomic<bool> carried_building_{false};
};

}  // namespace bvh_collision
