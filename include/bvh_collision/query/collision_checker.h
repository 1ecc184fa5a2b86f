// CollisionChecker: the queries of docs/design.md on plain C++ types, over one robot collision model
// built at construction (shapes, hierarchies, hulls, bounds, kinematics plan, motion rates) and
// never changed after. Each query kind has its own request/result header (self_query.h,
// environment_query.h, motion_query.h, batch_query.h, ray_query.h, self_filter_query.h) and its
// own source file (environment_check.cpp, motion_check.cpp, self_filter.cpp, ray_query.cpp;
// collision_checker.cpp builds the model and answers self checks and batches).
#pragma once

#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/query/batch_query.h"
#include "bvh_collision/world/environment.h"
#include "bvh_collision/query/environment_query.h"
#include "bvh_collision/query/motion_query.h"
#include "bvh_collision/query/ray_query.h"
#include "bvh_collision/model/robot_accelerators.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/world/filtered_scan.h"
#include "bvh_collision/query/self_query.h"
#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/narrowphase/shape_octree.h"
#include "bvh_collision/narrowphase/shape_pairs.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

class SceneChecker;

class CollisionChecker {
 public:
  CollisionChecker(RobotModel model, AllowedCollisionMatrix acm, const CheckerOptions& options = {});
  // This checker with one more proxy level (RobotAccelerators::with_proxy_level); the model is
  // shared. With two levels or more (and CheckerOptions::calibrate_proxies), the self pairs' exact
  // growth of certified motions is chosen again (query/motion_calibration.h).
  CollisionChecker with_proxy_level(double level, const std::atomic<bool>* cancel = nullptr) const;
  // This checker with the clearance grids of `cells` cells (RobotAccelerators::with_pair_clearance):
  // the same answers; the model is shared.
  CollisionChecker with_pair_clearance(std::size_t cells) const;

  // This checker carrying `bodies` (AttachedBody, world/environment.h; the model's carrying and
  // its accelerators'): each body one more link, named by its id, after the robot's links; the
  // state vector is the same. Throws as RobotCollisionModel::carrying.
  // With `proxies` false the copy has no proxy level (RobotAccelerators::carrying): built at
  // once, exact answers; the node carries so at first and swaps the levels in once built.
  CollisionChecker carrying(const std::vector<AttachedBody>& bodies, const NamedAllowedCollisions& allowed,
                            bool proxies = true) const;
  // The checker a query on `env` uses: this one carrying env.attached() (this one when it holds
  // none) with env's allowed collisions. Queries that take an environment read its objects only:
  // a checker that does not carry its attached bodies ignores them.
  CollisionChecker carrying(const Environment& env, bool proxies = true) const {
    return env.attached().empty() ? *this : carrying(env.attached(), env.allowed_collisions(), proxies);
  }
  // Does this checker carry every object `env` has attached (a carried link named by its id)?
  // The queries that take an environment (check_environment, check_batch, check_motion,
  // cast_ray) throw std::invalid_argument when it does not: a carried object left out would be a
  // collision missed. SceneChecker and the planning context carry them themselves.
  bool carries(const Environment& env) const {
    if (env.attached().empty()) return true;
    for (const AttachedBody& body : env.attached()) {
      const int l = model().link_index(body.id);
      if (l < static_cast<int>(m_->robot_link_count())) return false;
    }
    return true;
  }

  const RobotModel& model() const { return m_->robot(); }
  const AllowedCollisionMatrix& acm() const { return m_->acm(); }
  // What every query reads: shapes, hierarchies, bounds, kinematics, motion rates (immutable).
  const RobotCollisionModel& collision_model() const { return *m_; }
  // The model itself, shared: what a cache of its own geometry keys on (SceneChecker's held pairs).
  const std::shared_ptr<const RobotCollisionModel>& shared_collision_model() const { return m_; }
  // What is built from it to answer faster: proxy levels and clearance grids (immutable).
  const RobotAccelerators& accelerators() const { return *a_; }
  // The link pairs a self-collision query examines: both have geometry and the matrix allows
  // neither.
  const std::vector<std::pair<int, int>>& checked_pairs() const { return m_->checked_pairs(); }
  double link_padding(int link) const { return m_->paddings()[link]; }
  // The checked pairs (indices into checked_pairs()) whose relative pose can change when the
  // state variables `variables` change: a joint on the path between the two links is one of them,
  // mimics one, or is floating or planar. Every other pair is rigid while only these variables
  // move, so its answer cannot change: a planner moving one group checks those pairs once and
  // then only these (SelfCollisionRequest::only_pairs). Throws std::out_of_range for a bad index.
  std::vector<std::size_t> pairs_moved_by(const std::vector<int>& variables) const;

  // Throws std::invalid_argument naming the first variable of `state` that is not finite, the
  // message led by `what` (the query): such a state has no pose, and NaN poses compare as apart
  // everywhere. Every query of a state calls it first.
  void require_finite_state(const double* state, const char* what) const;

  // `state` holds model().variable_count() values (variable_names() order).
  SelfCollisionResult check_self(const double* state, const SelfCollisionRequest& request = {}) const;

  // Boolean self-collision for `count` states stored row by row; uses every core.
  std::vector<bool> check_self_batch(const double* states, std::size_t count, double tolerance = 0.0) const;
  // Boolean self checks of up to a few dozen states on the calling thread at a tolerance that
  // `proxies` (one of accelerators().proxy_levels(), with a batch) fits: the SIMD lanes for the
  // pairs the level answers, then the exact test for the pairs it leaves to it
  // (ProxyLevel::exact_pairs) in the states the lanes found free. out[i] = 1: state i collides.
  void check_self_in_lanes(const ProxyLevel& proxies, const double* states, std::size_t count, double tolerance, char* out,
                           SimdPath path = SimdPath::kAuto) const;

  // Boolean self and/or environment collision for `count` states stored row by row (1 = in
  // collision); uses every core when there is more than one state. `env` may be null when
  // request.environment is false.
  std::vector<char> check_batch(const double* states, std::size_t count, const Environment* env,
                                const BatchRequest& request) const;

  // The robot in `state` against the environment: every link with geometry (the allowed-collision
  // matrix is about link pairs) against the octree's occupied cubes and the objects, with the
  // links' padding.
  EnvironmentResult check_environment(const double* state, const Environment& env,
                                      const EnvironmentRequest& request = {}) const;

  // The self filter (docs/design.md), for a scan taken with the robot in `state`. A point on or within `padding` of a link (or inside a closed
  // link) is the robot, not an obstacle; a point whose ray from the sensor passes through a link is
  // in the robot's shadow and not an obstacle either. Neither is dropped outright: the sensor saw
  // through the space in front of the robot, so their rays still clear it, up to `padding` before
  // the ray first meets a link. A link that holds the sensor (within padding) casts no shadow: a
  // camera inside its mount's mesh would otherwise see nothing. Uses every core.
  // `root_pose` places the root link in the points' frame (a moving base). Objects the checker
  // carries (carrying()) take `carried_padding` when it is given (the node's ~object_padding).
  FilteredScan filter_scan(const double* state, const std::vector<ScanPoint>& points, const ScanPoint& sensor,
                           double padding, const Transform& root_pose = Transform::Identity(),
                           std::optional<double> carried_padding = std::nullopt) const;

  // The motion from `start` to `goal` (both variable_count() values). Throws std::invalid_argument
  // for a negative or non-finite resolution or tolerance. Certified (resolution 0) it is the
  // planner's engine (query/scene_checker.h), on a scene prepared for `env` and kept for the next
  // motion on the same snapshot (Environment::same_snapshot) and request: the first motion on a
  // snapshot pays the preparation (the object grid, the distance field), the rest nothing.
  MotionResult check_motion(const double* start, const double* goal, const Environment& env,
                            const MotionRequest& request = {}) const;

  // How far any point of `link` can move per unit change of each state variable, over every
  // configuration within the joint limits (revolute: the farthest its geometry can be from the
  // axis; prismatic: 1).
  const std::vector<double>& motion_rates(int link) const { return m_->motion_rates()[link]; }
  // How far any point of `link` can move per unit fraction of the straight segment from `start`
  // to `goal`: the rates weighted by each variable's change, widened where a prismatic joint on
  // the link's chain leaves its limits (the rates assume it does not).
  double link_speed(int link, const double* start, const double* goal) const;

  // The first link, object or occupied voxel along origin + s * direction, 0 <= s <= max_range
  // (max_range <= 0: unlimited), the robot in `state` with its root at `root_pose`. Throws
  // std::invalid_argument for a non-finite origin or a zero or non-finite direction.
  RayCastResult cast_ray(const double* state, const Environment& env, const Vec3& origin, const Vec3& direction,
                         double max_range, const Transform& root_pose = Transform::Identity()) const;

  // How far from the root link's origin any link geometry (with its padding) can get, over every
  // configuration within the joint limits: the default workspace is this plus a margin.
  double reach() const { return m_->reach(); }

  // Builds and keeps the octree's distance field over the robot's reach around `root_pose`
  // (Environment::octree_distance_field), which boolean checks and motions then use when asked
  // for a kept one; returns it (null when the octree is empty or the box too large). A node calls
  // this after each map change, off the query path.
  std::shared_ptr<const OctreeDistanceField> prepare_distance_field(const Environment& env,
                                                                    const Transform& root_pose = Transform::Identity()) const {
    return env.octree().empty() ? nullptr : octree_field(env, root_pose, true);
  }

  // The field prepare_distance_field kept for this octree, or null.
  std::shared_ptr<const OctreeDistanceField> kept_distance_field(const Environment& env,
                                                                 const Transform& root_pose = Transform::Identity()) const {
    return env.octree().empty() ? nullptr : octree_field(env, root_pose, false);
  }

  // Link BVHs built (only for links some checked pair needs), for reports.
  std::size_t built_meshes() const { return m_->meshes().size(); }

 private:
  void require_carried(const Environment& env) const {
    if (!carries(env)) {
      throw std::invalid_argument("the environment has attached objects this checker does not carry: query with checker.carrying(env)");
    }
  }
  bool pair_collides(int a, int b, const std::vector<Transform>& poses, const SelfCollisionRequest& request,
                     SelfCollisionResult& result) const;
  double pair_distance(int a, int b, const std::vector<Transform>& poses, double best,
                       const SelfCollisionRequest& request, SelfCollisionResult& result) const;

  bool split_fixed_links(std::vector<char>& moving, std::vector<char>& fixed) const;
  std::shared_ptr<const OctreeDistanceField> octree_field(const Environment& env, const Transform& root_pose,
                                                          bool build) const;
  // check_environment with the distance field already looked up (null: none).
  EnvironmentResult environment_check(const double* state, const Environment& env, const EnvironmentRequest& request,
                                      const OctreeDistanceField* field) const;
  // Boolean check of one link against the octree from its proxy (tolerance at least half its
  // level: narrowphase/proxy_octree.h), its contact into `result` when asked.
  bool link_proxy_meets_octree(int link, const Transform& pose, const LinkProxy& proxy, const Octree& tree,
                               const OctreeDistanceField& field, bool contacts, EnvironmentResult& result) const;
  bool link_meets_octree(int link, const Transform& pose, const Octree& tree, const EnvironmentRequest& request,
                         EnvironmentResult& result) const;
  void objects_near_robot(const std::vector<Transform>& poses, const ObjectList& objects,
                          const std::vector<char>* only, std::vector<ObjectBoxTree::Entry>& out) const;
  bool link_meets_object(int link, const Transform& pose, const CollisionObject& object,
                         const EnvironmentRequest& request, EnvironmentResult& result) const;
  double link_octree_distance(int link, const Transform& pose, const Octree& tree, double best, bool solids,
                              EnvironmentResult& result) const;
  double link_object_distance(int link, const Transform& pose, const CollisionObject& object, double best,
                              bool solids, EnvironmentResult& result) const;

  // Self filter primitives: is p on or within padding of the link; where does the ray first meet it.
  bool point_on_link(int link, const Transform& pose, const Vec3& p, double padding) const;
  double ray_meets_link(int link, const Transform& pose, const Vec3& origin, const Vec3& unit, double length) const;

  CollisionChecker(std::shared_ptr<const RobotCollisionModel> model, std::shared_ptr<const RobotAccelerators> accelerators)
      : m_(std::move(model)), a_(std::move(accelerators)) {}
  // `accelerators` with the pair exact growth chosen for them (query/motion_calibration.h).
  static std::shared_ptr<const RobotAccelerators> calibrated(const std::shared_ptr<const RobotCollisionModel>& model,
                                                             std::shared_ptr<RobotAccelerators> accelerators);

  // The scene the last certified motion was answered on (motion_check.cpp), kept for the next.
  struct PreparedMotions {
    std::mutex mutex;
    std::shared_ptr<const SceneChecker> scene;
  };
  std::shared_ptr<const SceneChecker> prepared_scene(const Environment& env, const MotionRequest& request) const;

  // Shared, never changed: a copy of the checker is cheap and answers the same.
  std::shared_ptr<const RobotCollisionModel> m_;
  std::shared_ptr<const RobotAccelerators> a_;
  // Shared by copies too (they answer alike on a snapshot); a scene checker's own copy has its own.
  std::shared_ptr<PreparedMotions> prepared_ = std::make_shared<PreparedMotions>();
};

}  // namespace bvh_collision
