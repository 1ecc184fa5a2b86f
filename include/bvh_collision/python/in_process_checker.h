// The checker as the Python module holds it (python/module.cpp binds it): one robot, one world
// (objects, attached objects, the octree), and the queries of docs/design.md over them with the
// same semantics, limits and errors as the C++ API. Plain C++ (no Python include), so the module
// is a thin adapter: arrays in, arrays out, the GIL released around every call into here.
//
// Thread safety: a change to the world (objects, clouds, attach) takes a lock and publishes a new
// snapshot; a query takes the current snapshot under the lock and runs without it, so queries
// from several Python threads run at once. Batches use the process's thread pool.
#pragma once

#include <cstddef>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"

namespace bvh_collision {

struct InProcessOptions {
  std::vector<std::string> package_paths;  // searched before ROS_PACKAGE_PATH for package:// URIs
  double padding = 0.0;                    // every link's padding (m)
  std::vector<double> proxy_levels;        // bounded-error proxy levels (m), built at construction
  std::string proxy_cache;                 // a folder where built proxies are kept (empty: none)
  double octree_resolution = 0.02;         // the world's octree voxel edge (m)
};

// What a batch of states asks (check_states).
struct StatesQuery {
  bool self = true, environment = true;
  double tolerance = 0.0;
  bool distance = false;  // also each state's distance and nearest pair
};

// What each state of a batch answers. `distance` and the pair only with StatesQuery::distance:
// 0 in collision (the pair one that collides), inf with nothing to be near.
struct StatesAnswer {
  std::vector<char> valid;
  std::vector<double> distance;
  std::vector<std::string> nearest_a, nearest_b;
};

struct MotionsAnswer {
  std::vector<char> valid;
  std::vector<double> last_valid_fraction;
};

// One contact of a state: two links (self) or a link and an object id or "octree".
struct StateContact {
  std::string a, b;
  bool self = true;
  Vec3 position = Vec3::Zero();  // world frame (self contacts: the root link's frame, the same here)
};

class InProcessChecker {
 public:
  // `urdf` and `srdf` are XML text or paths to files (text when it starts with '<'); the SRDF
  // may be empty. Throws std::invalid_argument or RobotLoadError naming what is wrong.
  InProcessChecker(const std::string& urdf, const std::string& srdf, const InProcessOptions& options);

  // The robot's checker now (add_proxy_level swaps it; a query holds the one it started with).
  std::shared_ptr<const CollisionChecker> checker() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return checker_;
  }
  // The same model for every checker of this robot (proxy levels share it).
  const RobotModel& model() const { return *model_; }
  std::size_t dof() const { return model().variable_count(); }

  // `states`: count rows of dof() values. Throws std::invalid_argument for a value that is not
  // finite (naming the state and the variable) or a bad tolerance.
  StatesAnswer check_states(const double* states, std::size_t count, const StatesQuery& query) const;
  // Certified straight motions (the planner's engine), row r from starts[r] to goals[r].
  MotionsAnswer check_motions(const double* starts, const double* goals, std::size_t count, const StatesQuery& query) const;
  std::vector<StateContact> contacts(const double* state, bool self, bool environment) const;
  RayCastResult cast_ray(const double* state, const Vec3& origin, const Vec3& direction, double max_range) const;

  // The world. Objects: as Environment::add_object (replacing one of the same id).
  void add_object(const std::string& id, const ObjectShape& shape, const Transform& pose);
  bool remove_object(const std::string& id);
  std::vector<std::string> object_ids() const;
  // A scene file (MoveIt .scene or PlanningScene YAML) applied to the world, its frames placed
  // with the robot in `state` (root link at the origin; "world" and the SRDF's mount name it).
  // Returns its warnings. Nothing changes when it throws.
  std::vector<std::string> load_scene(const std::string& path, const double* state);
  // The world object `id` hung from `link` where it is now, the robot in `state`.
  void attach(const std::string& id, const std::string& link, const double* state, const std::vector<std::string>& touch_links);
  // Back into the world where the robot in `state` holds it. False when nothing of that id is held.
  bool detach(const std::string& id, const double* state);
  std::vector<std::string> attached_ids() const;

  // A cloud (world frame) from a sensor at `origin`, as the node inserts one: with `state`, the
  // self filter first (points within `self_filter_padding` of the robot, or in its shadow, only
  // clear); rays beyond max_range (< 0: unlimited) only clear. Returns the scan's counts.
  ScanStats insert_cloud(const std::vector<ScanPoint>& points, const ScanPoint& origin, const double* state,
                         double max_range, double self_filter_padding);
  void load_octree(const std::string& path);
  void save_octree(const std::string& path) const;
  void clear_octree();
  std::size_t occupied_voxels() const;
  double octree_resolution() const;

  // Adds a proxy level (m) to the robot (built now, or read from the proxy cache).
  void add_proxy_level(double level);
  std::vector<double> proxy_levels() const;

 private:
  std::shared_ptr<const Environment> snapshot() const;
  // The checker that carries what `env` holds (the robot itself when it holds nothing).
  std::shared_ptr<const CollisionChecker> carrying(const Environment& env) const;
  std::shared_ptr<const SceneChecker> scene(const std::shared_ptr<const Environment>& env, const StatesQuery& query) const;
  void publish(Environment next);
  Transform link_pose(int link, const double* state) const;
  void require_state(const double* state, const char* what) const;
  // Every row finite; else std::invalid_argument naming `what` and the row.
  void require_states(const double* states, std::size_t count, const char* what) const;

  std::string srdf_;
  std::shared_ptr<const CollisionChecker> checker_;
  const RobotModel* model_;
  mutable std::mutex mutex_;
  std::shared_ptr<const Environment> world_;
  mutable std::shared_ptr<const CollisionChecker> carrying_;  // for world_'s attached list
  mutable std::shared_ptr<const SceneChecker> scene_;         // the last prepared scene
  mutable StatesQuery scene_query_;
};

}  // namespace bvh_collision
