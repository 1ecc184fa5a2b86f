// The robot as the collision queries see it, built once and never changed after: per link its
// shapes (exact primitives, or meshes with their OBB hierarchies and convex hulls), a bounding
// sphere and padding; the link pairs a self check examines; the kinematics plan of the links that
// matter; and how fast any point of a link can move per unit of each state variable. Every query
// module (self, environment, motion, self filter, ray) reads it; none writes it, so checkers that
// share one (copies of a CollisionChecker) share it safely between threads.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/world/environment.h"
#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/limits.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/narrowphase/compound_shape.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

struct CheckerOptions {
  double padding = 0.0;                        // every link's padding (m)...
  std::map<std::string, double> link_padding;  // ...unless named here
  // How link BVHs are built: two triangles per leaf answered self-collision, boolean and
  // distance, with fewer instructions than one or three (docs/performance.md).
  BuildOptions bvh = {BuildMethod::kSah, 2};
  // The accelerators built beside the model (model/robot_accelerators.h) read the next three.
  // Proxy levels e (m) for bounded-error sphere proxies (narrowphase/link_proxy.h), built at
  // construction. A boolean self check at tolerance t >= e answers from the coarsest such level.
  // Empty by default: their build delays the start (one core: panda 0.61 s at 10 mm, 2.9 s at
  // 2 mm; pr2 2.6 s at 10 mm; docs/performance.md); with_proxy_level adds one later (the node
  // builds 5, 10 and 20 mm so, after start-up). Levels of 5 mm and up pay; 2 mm was slower than
  // the exact check on panda.
  std::vector<double> proxy_levels;
  // A folder where link proxies and clearance grids are kept by content
  // (narrowphase/link_proxy_cache.h, model/pair_clearance_cache.h): a level whose links are there,
  // and grids for the same robot, pairs and cell budget, are read instead of built. Empty: none
  // (the node's ~proxy_cache has one).
  std::string proxy_cache;
  // Time each self pair both ways on a fixed sample of states when a level is built
  // (model/proxy_calibration.h) and let the proxies answer only the pairs where they were not
  // slower (panda: a few ms a level). Off: the proxies answer every pair at a tolerance that
  // fits them (tests of the proxies' contract, benchmarks of the proxies alone).
  bool calibrate_proxies = true;
  // Grids of proven clearance for the self pairs one or two variables move
  // (model/pair_clearance.h): a boolean self check skips such a pair with one lookup when its
  // bound clears the padding, and a certified motion an interval (PairClearance::clear_over).
  // 0 cells: none built.
  std::size_t pair_clearance_cells = 4096;
  // How much one robot and one query may ask for (geometry/limits.h): construction refuses a
  // robot with more links or checked pairs, check_motion a fixed-step motion with more states,
  // check_batch a larger batch, each with LimitExceeded.
  Limits limits;
};

// One collision element of a link.
// One shape of a link, in the link frame: a part of the link's compound (its mesh index into
// RobotCollisionModel::meshes(), or -1 for an exact primitive).
using LinkShape = CompoundPart;

// A sphere in the link frame that holds every shape of the link.
struct LinkBound {
  Vec3 center = Vec3::Zero();
  double radius = -1.0;  // < 0: no geometry
};

// A prismatic joint on a link's chain, as the motion bound needs it.
struct SlideBound {
  int variable = -1;
  double multiplier = 1.0;  // |multiplier| of the (mimic) prismatic joint
  double travel = 0.0;      // the largest |value| the rates assumed
};

// A link's motion rate and turn multiplier for one variable that moves it (the nonzero entries of
// motion_rates and motion_turns, by variable).
struct MotionTerm {
  int variable = -1;
  double rate = 0.0, turn = 0.0;
};

class RobotCollisionModel {
 public:
  RobotCollisionModel(RobotModel robot, AllowedCollisionMatrix acm, const CheckerOptions& options);

  // This model carrying `bodies` (AttachedBody, world/environment.h): each one more link, named
  // by its id and hung from its link (RobotModel::with_fixed_link), with its shapes, padded as a
  // link of that name would be (CheckerOptions::link_padding, else the default). Its self pairs
  // come after the model's, whose indices stay: every link or body with geometry except its own
  // link, its touch links, and those `allowed` lets it touch (by name). Throws
  // std::invalid_argument for an unknown link or touch link, an id a link has, or an id twice;
  // LimitExceeded past the links or pairs allowed.
  RobotCollisionModel carrying(const std::vector<AttachedBody>& bodies, const NamedAllowedCollisions& allowed) const;
  // The robot's own links: carried bodies are the links from here on.
  std::size_t robot_link_count() const { return robot_links_; }

  const RobotModel& robot() const { return robot_; }
  const AllowedCollisionMatrix& acm() const { return acm_; }
  const KinematicsPlan& kinematics() const { return kinematics_; }  // poses of the modelled links only
  const std::vector<Bvh<Obb>>& meshes() const { return meshes_; }
  const std::vector<ConvexHull>& hulls() const { return hulls_; }  // per mesh
  const std::vector<std::vector<LinkShape>>& shapes() const { return shapes_; }  // per link
  const std::vector<LinkBound>& bounds() const { return bounds_; }               // per link
  const std::vector<double>& paddings() const { return padding_; }               // per link
  // Both links have geometry and the matrix allows neither.
  const std::vector<std::pair<int, int>>& checked_pairs() const { return checked_pairs_; }
  // Per link, per state variable: how far any point of the link moves per unit of the variable
  // within the joint limits; the revolute multipliers on its chain; its prismatic joints.
  const std::vector<std::vector<double>>& motion_rates() const { return motion_rates_; }
  const std::vector<std::vector<double>>& motion_turns() const { return motion_turns_; }
  const std::vector<std::vector<SlideBound>>& motion_slides() const { return motion_slides_; }
  // The same, per link only the variables that move it, in variable order (a link speed sums
  // these: pr2's links are moved by a few of its 40-odd variables).
  const std::vector<std::vector<MotionTerm>>& motion_terms() const { return motion_terms_; }
  double reach() const { return reach_; }
  const Limits& limits() const { return limits_; }
  // A shape as the narrowphase takes it.
  ShapeRef ref(const LinkShape& s) const { return shape_ref(meshes_, hulls_, s.mesh, s.primitive); }
  // Link `link`'s shapes so, in the link frame.
  std::vector<BodyShape> placed_shapes(int link) const;
  // Link `link` as one shape of the narrowphase, all its parts.
  CompoundShape compound(int link) const { return CompoundShape(shapes_[static_cast<std::size_t>(link)], meshes_, hulls_); }

 private:
  void build_shapes(const CheckerOptions& options, const std::vector<bool>& needed);
  void build_meshes(const std::vector<const TriangleMesh*>& distinct, const BuildOptions& bvh);
  void compute_motion_rates();
  void add_body(const AttachedBody& body, const NamedAllowedCollisions& allowed);

  RobotModel robot_;
  AllowedCollisionMatrix acm_;
  KinematicsPlan kinematics_;
  std::vector<Bvh<Obb>> meshes_;
  std::vector<ConvexHull> hulls_;  // per mesh: bounds and often settles distances (shape_pairs.cpp)
  std::vector<std::vector<LinkShape>> shapes_;
  std::vector<LinkBound> bounds_;
  std::vector<double> padding_;
  std::vector<std::pair<int, int>> checked_pairs_;
  std::vector<std::vector<double>> motion_rates_;
  std::vector<std::vector<double>> motion_turns_;
  std::vector<std::vector<SlideBound>> motion_slides_;
  std::vector<std::vector<MotionTerm>> motion_terms_;
  double reach_ = 0.0;
  Limits limits_;
  double default_padding_ = 0.0;
  std::map<std::string, double> link_padding_;  // CheckerOptions', for carried bodies
  std::size_t robot_links_ = 0;
};

}  // namespace bvh_collision
