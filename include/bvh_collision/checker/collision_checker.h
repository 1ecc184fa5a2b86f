// CollisionChecker: the queries of DESIGN.md on plain C++ types. This part: self-collision of
// one configuration or a batch, boolean, all pairs, contacts, and minimum distance.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/checker/detail/shape_pairs.h"
#include "bvh_collision/checker/environment.h"
#include "bvh_collision/checker/mesh_octree.h"
#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

struct CheckerOptions {
  double padding = 0.0;                        // every link's padding (m)...
  std::map<std::string, double> link_padding;  // ...unless named here
  // How link BVHs are built: two triangles per leaf took 6-15% fewer instructions than one for
  // boolean and distance self-collision on panda, ur5e and pr2 (three was worse on pr2).
  BuildOptions bvh = {BuildMethod::kSah, 2};
};

struct SelfCollisionRequest {
  // DESIGN.md section 2. With `distance`, the reported minimum distance may also exceed the true
  // one by up to this much (never fall below it): the search prunes what cannot gain more.
  double tolerance = 0.0;
  bool all_pairs = false;        // false: stop at the first colliding pair
  std::size_t max_contacts = 0;  // contacts per colliding pair (0: none)
  bool distance = false;         // also the minimum distance over checked pairs
  bool solids = true;            // closed meshes bound solids
  // Only these checked pairs (indices into CollisionChecker::checked_pairs(), e.g. from
  // pairs_moved_by); null: all of them. Not owned: it must outlive the query.
  const std::vector<std::size_t>* only_pairs = nullptr;
};

struct LinkContact {
  int link_a = -1, link_b = -1;
  MeshContact contact;
};

struct SelfCollisionResult {
  bool collision = false;
  std::vector<std::pair<int, int>> colliding_pairs;  // link indices, a < b, in checking order
  std::vector<LinkContact> contacts;
  double min_distance = std::numeric_limits<double>::quiet_NaN();  // only when asked
  int closest_a = -1, closest_b = -1;
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  // witnesses in the root link's frame
  QueryStats stats;
};

struct EnvironmentRequest {
  double tolerance = 0.0;  // DESIGN.md section 2
  bool all_links = false;  // false: stop at the first colliding link
  bool distance = false;   // also the minimum distance from the robot to any obstacle
  bool solids = true;      // closed meshes bound solids; occupied space is solid
  bool octree = true;      // check against the octree...
  bool objects = true;     // ...and against the collision objects
  Transform root_pose;     // the root link in the environment's (world) frame: a moving base
};

struct EnvironmentContact {
  int link = -1;
  std::string object;            // the object's id; empty for the octree
  Octree::Leaf voxel;            // the occupied cube, for the octree
  Vec3 position = Vec3::Zero();  // world frame
};

struct EnvironmentResult {
  bool collision = false;
  std::vector<EnvironmentContact> contacts;  // one per colliding (link, obstacle), in checking order
  double min_distance = std::numeric_limits<double>::quiet_NaN();  // only when asked; inf: no obstacle
  int closest_link = -1;
  std::string closest_object;  // empty: the octree (when closest_link >= 0)
  Octree::Leaf closest_voxel;
  Vec3 point_link = Vec3::Zero(), point_obstacle = Vec3::Zero();  // world frame witnesses
  QueryStats stats;
};

// The straight joint-space motion from start to goal (DESIGN.md section 4, check_motion).
struct MotionRequest {
  bool self = true, environment = true;
  // > 0: states every `resolution` of joint motion (max norm over joints, rad or m), both ends
  // included. 0: certified: each step is shorter than the clearance at its start divided by a
  // bound on how fast any point of any link moves, so no collision hides between states.
  double resolution = 0.0;
  double tolerance = 0.0;     // DESIGN.md section 2
  Transform root_pose;        // the root link in the world frame
  // Certified: a motion that comes within this of collision counts as colliding. Advancement
  // by clearance can only creep towards an exact contact, never reach it; this bounds the steps
  // (about log(clearance / min_clearance) of them near a contact) and is a tolerance of its own.
  double min_clearance = 1e-5;
  std::size_t max_states = 20000;  // certified: beyond this the motion is not certified (invalid)
};

struct MotionResult {
  bool valid = false;
  double last_valid_fraction = 0.0;  // the last state checked free before the first collision (1 when valid)
  std::size_t states_checked = 0;
  bool certified = false;    // the whole motion (or up to the collision) was certified
  std::string message;       // why a certified check gave up, when it did
};

// A batch of states checked for collision, boolean (check_batch).
struct BatchRequest {
  bool self = true, environment = true;
  double tolerance = 0.0;  // DESIGN.md section 2
  Transform root_pose;     // the root link in the world frame
};

// The first body along a ray: a link, a collision object, or an occupied voxel.
struct RayCastResult {
  bool hit = false;
  double distance = std::numeric_limits<double>::infinity();  // along the ray from its origin
  Vec3 point = Vec3::Zero();
  int link = -1;           // the link hit, or -1
  std::string object;      // the object hit, or empty
  bool octree = false;     // an occupied voxel was hit
};

// A scan split by the self filter, ready for insert_scan(tree, obstacles, clear_only, sensor).
struct FilteredScan {
  std::vector<ScanPoint> obstacles;   // kept, in scan order (invalid points too: insert_scan counts them)
  std::vector<ScanPoint> clear_only;  // robot points and shadows, cut to `padding` before the robot
  std::size_t on_robot = 0;           // points on or within padding of a link, or inside a closed one
  std::size_t shadowed = 0;           // points whose ray from the sensor passes through a link
};

class CollisionChecker {
 public:
  CollisionChecker(RobotModel model, AllowedCollisionMatrix acm, const CheckerOptions& options = {});

  const RobotModel& model() const { return model_; }
  const AllowedCollisionMatrix& acm() const { return acm_; }
  // The link pairs a self-collision query examines: both have geometry and the matrix allows
  // neither.
  const std::vector<std::pair<int, int>>& checked_pairs() const { return checked_pairs_; }
  double link_padding(int link) const { return padding_[link]; }
  // The checked pairs (indices into checked_pairs()) whose relative pose can change when the
  // state variables `variables` change: a joint on the path between the two links is one of them,
  // mimics one, or is floating or planar. Every other pair is rigid while only these variables
  // move, so its answer cannot change: a planner moving one group checks those pairs once and
  // then only these (SelfCollisionRequest::only_pairs). Throws std::out_of_range for a bad index.
  std::vector<std::size_t> pairs_moved_by(const std::vector<int>& variables) const;

  // `state` holds model().variable_count() values (variable_names() order).
  SelfCollisionResult check_self(const double* state, const SelfCollisionRequest& request = {}) const;

  // Boolean self-collision for `count` states stored row by row; uses every core.
  std::vector<bool> check_self_batch(const double* states, std::size_t count, double tolerance = 0.0) const;

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

  // The self filter (DESIGN.md section 3), for a scan taken with the robot in `state`. A point on or within `padding` of a link (or inside a closed
  // link) is the robot, not an obstacle; a point whose ray from the sensor passes through a link is
  // in the robot's shadow and not an obstacle either. Neither is dropped outright: the sensor saw
  // through the space in front of the robot, so their rays still clear it, up to `padding` before
  // the ray first meets a link. A link that holds the sensor (within padding) casts no shadow: a
  // camera inside its mount's mesh would otherwise see nothing. Uses every core.
  // `root_pose` places the root link in the points' frame (a moving base).
  FilteredScan filter_scan(const double* state, const std::vector<ScanPoint>& points, const ScanPoint& sensor,
                           double padding, const Transform& root_pose = Transform::Identity()) const;

  // The motion from `start` to `goal` (both variable_count() values). Throws std::invalid_argument
  // for a negative or non-finite resolution or tolerance.
  MotionResult check_motion(const double* start, const double* goal, const Environment& env,
                            const MotionRequest& request = {}) const;

  // How far any point of `link` can move per unit change of each state variable, over every
  // configuration within the joint limits (revolute: the farthest its geometry can be from the
  // axis; prismatic: 1).
  const std::vector<double>& motion_rates(int link) const { return motion_rates_[link]; }
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
  double reach() const { return reach_; }

  // Link BVHs built (only for links some checked pair needs), for reports.
  std::size_t built_meshes() const { return meshes_.size(); }

 private:
  struct Shape {
    Transform origin;   // in the link frame
    int mesh = -1;      // index into meshes_, or -1 for an exact primitive
    Primitive primitive;
  };
  struct LinkBound {
    Vec3 center = Vec3::Zero();  // link frame
    double radius = -1.0;        // < 0: no geometry
  };

  bool pair_collides(int a, int b, const std::vector<Transform>& poses, const SelfCollisionRequest& request,
                     SelfCollisionResult& result) const;
  double pair_distance(int a, int b, const std::vector<Transform>& poses, double best,
                       const SelfCollisionRequest& request, SelfCollisionResult& result) const;
  detail::ShapeRef ref(const Shape& s) const {
    return s.mesh < 0 ? detail::ShapeRef{nullptr, nullptr, s.primitive}
                      : detail::ShapeRef{&meshes_[s.mesh], &hulls_[s.mesh], Primitive{}};
  }

  bool link_meets_octree(int link, const Transform& pose, const Octree& tree, const EnvironmentRequest& request,
                         EnvironmentResult& result) const;
  bool link_meets_object(int link, const Transform& pose, const CollisionObject& object,
                         const EnvironmentRequest& request, EnvironmentResult& result) const;
  double link_octree_distance(int link, const Transform& pose, const Octree& tree, double best, bool solids,
                              EnvironmentResult& result) const;
  double link_object_distance(int link, const Transform& pose, const CollisionObject& object, double best,
                              bool solids, EnvironmentResult& result) const;

  // Self filter primitives: is p on or within padding of the link; where does the ray first meet it.
  bool point_on_link(int link, const Transform& pose, const Vec3& p, double padding) const;
  double ray_meets_link(int link, const Transform& pose, const Vec3& origin, const Vec3& unit, double length) const;

  void compute_motion_rates();

  RobotModel model_;
  AllowedCollisionMatrix acm_;
  KinematicsPlan kinematics_;  // poses of the modelled links only
  std::vector<Bvh<Obb>> meshes_;
  std::vector<ConvexHull> hulls_;  // per mesh: bounds and often settles distances (see .cpp)
  std::vector<std::vector<Shape>> shapes_;  // per link
  std::vector<LinkBound> bounds_;
  std::vector<double> padding_;
  std::vector<std::pair<int, int>> checked_pairs_;
  std::vector<std::vector<double>> motion_rates_;  // per link, per state variable
  std::vector<std::vector<double>> motion_turns_;  // per link, per variable: revolute multipliers on its chain
  struct SlideBound {
    int variable = -1;
    double multiplier = 1.0;  // |multiplier| of the (mimic) prismatic joint
    double travel = 0.0;      // the largest |value| the rates assumed
  };
  std::vector<std::vector<SlideBound>> motion_slides_;  // per link: prismatic joints on its chain
  double reach_ = 0.0;
};

}  // namespace bvh_collision
