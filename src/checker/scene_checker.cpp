// SceneChecker: one state and one motion against one environment snapshot (scene_checker.h).
#include "bvh_collision/checker/scene_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <stdexcept>

#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {

// ---- ObjectGrid ------------------------------------------------------------------------------

namespace {

// The world box of a primitive or mesh bound at `pose`: |R| half-extents around the centre.
void world_box(const Transform& pose, const Vec3& centre, const Vec3& half, Vec3& lo, Vec3& hi) {
  const Vec3 c = pose * centre;
  const Vec3 e = pose.R.cwiseAbs() * half;
  const double m = pose_margin(c.norm() + half.norm());
  lo = c - e - Vec3::Constant(m);
  hi = c + e + Vec3::Constant(m);
}

// The squared distance from p to the box [lo, hi].
double squared_box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.cwiseMax(lo).cwiseMin(hi) - p).squaredNorm();
}

}  // namespace

ObjectGrid::ObjectGrid(const std::vector<CollisionObject>& objects, const Vec3& lo, const Vec3& hi, double reach,
                       double cell)
    : origin_(lo), cell_(cell), reach_(reach) {
  for (const CollisionObject& o : objects) {
    Solid s;
    s.to_local = o.pose.inverse();
    s.primitive = o.mesh == nullptr || o.shape.kind == ObjectShape::Kind::kBox;
    s.shape = o.mesh == nullptr ? o.primitive : Primitive::box(o.shape.size);
    s.centre = o.pose * o.bound_center;
    s.radius = o.bound_radius;
    world_box(o.pose, s.primitive ? Vec3::Zero() : o.bound_center,
              s.primitive ? half_extents(s.shape) : Vec3::Constant(o.bound_radius), s.lo, s.hi);
    s.margin = pose_margin(s.centre.norm() + s.radius);
    solids_.push_back(s);
  }
  for (int i = 0; i < 3; ++i) n_[i] = std::max(1, static_cast<int>(std::ceil((hi[i] - lo[i]) / cell)));
  const std::size_t cells = static_cast<std::size_t>(n_[0]) * n_[1] * n_[2];
  start_.assign(cells + 1, 0);
  // A cell lists an object when the object's box comes within reach of the cell's box (the ball
  // of a query centred in the cell, of radius up to reach, can then meet it).
  const double half_diagonal = 0.5 * std::sqrt(3.0) * cell;
  std::vector<std::vector<std::uint32_t>> lists(cells);
  for (std::size_t o = 0; o < solids_.size(); ++o) {
    const Solid& s = solids_[o];
    int first[3], last[3];
    for (int i = 0; i < 3; ++i) {
      first[i] = std::clamp(static_cast<int>(std::floor((s.lo[i] - reach - lo[i]) / cell)), 0, n_[i] - 1);
      last[i] = std::clamp(static_cast<int>(std::floor((s.hi[i] + reach - lo[i]) / cell)), 0, n_[i] - 1);
    }
    for (int z = first[2]; z <= last[2]; ++z) {
      for (int y = first[1]; y <= last[1]; ++y) {
        for (int x = first[0]; x <= last[0]; ++x) {
          const Vec3 centre = lo + cell * Vec3(x + 0.5, y + 0.5, z + 0.5);
          const double within = reach + half_diagonal;
          if (squared_box_distance(centre, s.lo, s.hi) > within * within * (1 + 1e-9)) continue;
          lists[(static_cast<std::size_t>(z) * n_[1] + y) * n_[0] + x].push_back(static_cast<std::uint32_t>(o));
        }
      }
    }
  }
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] = start_[c] + static_cast<std::uint32_t>(lists[c].size());
  list_.reserve(start_.back());
  for (const auto& l : lists) list_.insert(list_.end(), l.begin(), l.end());
}

int ObjectGrid::cell_of(const Vec3& p) const {
  int at[3];
  for (int i = 0; i < 3; ++i) {
    const double f = (p[i] - origin_[i]) / cell_;
    if (!(f >= 0.0) || f >= n_[i]) return -1;  // outside (or not a number): every object
    at[i] = static_cast<int>(f);
  }
  return (at[2] * n_[1] + at[1]) * n_[0] + at[0];
}

// How deep p (object frame) lies inside the primitive: the radius of the largest ball around p
// inside it (0 or less outside). Convex solids: the smallest distance to a bounding surface.
// Cones are not bounded this way here (-infinity: no proof from them).
double inscribed_depth(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kSphere: return prim.radius - p.norm();
    case Primitive::Kind::kBox: return (prim.half - p.cwiseAbs()).minCoeff();
    case Primitive::Kind::kCylinder: return std::min(prim.radius - std::hypot(p.x(), p.y()), prim.half_length - std::abs(p.z()));
    case Primitive::Kind::kCapsule: {
      const Vec3 axis_point(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      return prim.radius - (p - axis_point).norm();
    }
    case Primitive::Kind::kCone: break;
  }
  return -std::numeric_limits<double>::infinity();
}

double ObjectGrid::depth(int o, const Vec3& centre) const {
  const Solid& s = solids_[o];
  if (!s.primitive) return -std::numeric_limits<double>::infinity();
  // Less the rounding of the transform and of the depth at this scale.
  return inscribed_depth(s.shape, s.to_local * centre) - 2.0 * (s.margin + pose_margin(centre.norm()));
}

bool ObjectGrid::ball_meets(int o, const Vec3& centre, double radius) const {
  const Solid& s = solids_[o];
  const double reach = radius + s.margin + pose_margin(centre.norm());
  if (squared_box_distance(centre, s.lo, s.hi) > reach * reach) return false;
  if (!s.primitive) return (centre - s.centre).squaredNorm() <= (reach + s.radius) * (reach + s.radius);
  const Vec3 p = s.to_local * centre;
  return (closest_point(s.shape, p) - p).squaredNorm() <= reach * reach;
}

// ---- SceneChecker: set-up ----------------------------------------------------------------------

namespace {

struct Scratch {
  std::vector<double> growth, state, speed, pair_speed, pair_growth, from, to;
  std::vector<int> pending;  // a motion's components still to certify, per interval (check_interval)
  std::vector<char> tolerant, near;  // per component: may the tolerance's shortcut take it?
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

// The levels tests go through, coarsest first, down to the finest that serves `tolerance`: at
// a tolerance the coarsest level up to half of it (or up to it), exact: every level.
std::vector<const ProxyLevel*> levels_for(const RobotCollisionModel& m, double tolerance) {
  const ProxyLevel* finest = nullptr;
  if (tolerance > 0.0) finest = m.proxies_for(tolerance / 2);
  if (finest == nullptr && tolerance > 0.0) finest = m.proxies_for(tolerance);
  std::vector<const ProxyLevel*> out;
  for (const ProxyLevel& p : m.proxy_levels()) {
    if (finest == nullptr || p.level >= finest->level) out.push_back(&p);
  }
  std::sort(out.begin(), out.end(), [](const ProxyLevel* a, const ProxyLevel* b) { return a->level > b->level; });
  return out;
}

}  // namespace

SceneChecker::SceneChecker(CollisionChecker checker, std::shared_ptr<const Environment> environment,
                           const SceneCheckOptions& options)
    : checker_(std::move(checker)), env_(std::move(environment)), options_(options) {
  if (!env_) throw std::invalid_argument("scene checker: no environment");
  if (!is_rigid(options.root_pose)) throw std::invalid_argument("scene checker: the root pose is not a finite rigid transform");
  if (!std::isfinite(options.tolerance) || options.tolerance < 0.0) throw std::invalid_argument("scene checker: tolerance must be finite and >= 0");
  const RobotCollisionModel& m = checker_.collision_model();
  proxies_ = levels_for(m, options.tolerance);
  level_ = proxies_.empty() ? 0.0 : proxies_.back()->level;
  proxies_decide_self_ = !proxies_.empty() && options.tolerance >= level_;
  proxies_decide_objects_ = !proxies_.empty() && options.tolerance >= level_ / 2;
  double reach = 0.0;
  for (std::size_t l = 0; l < m.shapes().size(); ++l) {
    if (m.shapes()[l].empty()) continue;
    links_.push_back(static_cast<int>(l));
    reach = std::max(reach, m.bounds()[l].radius + m.paddings()[l]);
  }
  relative_pair_rates();
  root_at_origin_ = options.root_pose.R == Mat3::Identity() && options.root_pose.t == Vec3::Zero();
  // Self pairs first (a state's self collisions are the likelier), then each link's environment.
  for (std::size_t p = 0; p < pair_rates_.size() && options.self; ++p) components_.push_back(static_cast<int>(p));
  for (const int l : links_) {
    if (options.environment) components_.push_back(static_cast<int>(pair_rates_.size()) + l);
  }
  if (options.environment && !env_->objects().empty()) {
    // Cells of 10 cm over the reach around the root; queries up to the largest link ball plus
    // 5 cm of growth use the cell's list.
    const Vec3 around = Vec3::Constant(checker_.reach() + 0.1);
    grid_ = ObjectGrid(env_->objects(), options.root_pose.t - around, options.root_pose.t + around, reach + 0.05, 0.1);
  }
  if (options.environment && !env_->octree().empty()) {
    field_ = checker_.kept_distance_field(*env_, options.root_pose);
    if (!field_) field_ = checker_.prepare_distance_field(*env_, options.root_pose);
  }
}

// Per checked pair, how fast the distance between its links can change per unit of each state
// variable: only the joints on the path between the two links change their relative pose (the
// deepest common ancestor's frame sees the joints above it move both alike, and a distance is the
// same in any frame), each at the rate of the link it moves (RobotCollisionModel::motion_rates:
// the farthest that link's geometry gets from the joint's axis). A pair with a prismatic joint
// on a chain (whose rate assumes its travel) or a joint that is no state variable keeps the sum
// of its links' own bounds.
void SceneChecker::relative_pair_rates() {
  const RobotModel& robot = checker_.model();
  const RobotCollisionModel& m = checker_.collision_model();
  std::vector<std::vector<int>> above(robot.links().size());  // joints from the root, per link
  for (const int j : robot.joint_order()) {
    const RobotJoint& joint = robot.joints()[j];
    above[joint.child_link] = above[joint.parent_link];
    if (joint.type != JointType::kFixed) above[joint.child_link].push_back(j);
  }
  auto variable_of = [&](int j) {
    const RobotJoint& joint = robot.joints()[j];
    return joint.mimic >= 0 ? robot.joints()[joint.mimic].variable : joint.variable;
  };
  for (const auto& [a, b] : m.checked_pairs()) {
    PairRates rates;
    rates.relative = m.motion_slides()[a].empty() && m.motion_slides()[b].empty();
    std::vector<double> w(robot.variable_count(), 0.0);
    for (const auto& [link, other] : {std::pair<int, int>{a, b}, std::pair<int, int>{b, a}}) {
      std::vector<char> moves(robot.variable_count(), 0);  // a joint of this side only has the variable
      for (const int j : above[link]) {
        if (std::find(above[other].begin(), above[other].end(), j) != above[other].end()) continue;  // moves both alike
        const int v = variable_of(j);
        if (v < 0) {
          rates.relative = false;
          continue;
        }
        moves[v] = 1;
      }
      // The link's rate for a variable covers every joint of its chain that the variable drives.
      for (std::size_t v = 0; v < w.size(); ++v) w[v] += moves[v] ? m.motion_rates()[link][v] : 0.0;
    }
    for (std::size_t v = 0; v < w.size(); ++v) {
      if (w[v] > 0.0) rates.weights.emplace_back(static_cast<int>(v), w[v]);
    }
    pair_rates_.push_back(std::move(rates));
  }
}

double SceneChecker::link_growth(int link, const double* start, const double* goal, double half) const {
  const double g = checker_.link_speed(link, start, goal) * half;
  return g * (1.0 + 1e-9) + pose_margin(g);
}

double SceneChecker::pair_growth(std::size_t pair, const double* start, const double* goal, double half) const {
  const auto [a, b] = checker_.collision_model().checked_pairs()[pair];
  double speed = 0.0;
  if (!pair_rates_[pair].relative) {
    speed = checker_.link_speed(a, start, goal) + checker_.link_speed(b, start, goal);
  } else {
    for (const auto& [v, w] : pair_rates_[pair].weights) speed += w * std::abs(goal[v] - start[v]);
  }
  const double g = speed * half;
  return g * (1.0 + 1e-9) + pose_margin(g);
}

void SceneChecker::pose_links(const double* state, Posed& posed) const {
  const RobotCollisionModel& m = checker_.collision_model();
  posed.state = state;
  m.kinematics().compute(state, posed.poses);
  posed.centres.resize(posed.poses.size());
  const bool moved = !root_at_origin_;
  for (const int l : links_) {
    if (moved) posed.poses[l] = options_.root_pose * posed.poses[l];
    const Transform& pose = posed.poses[l];
    const Vec3& c = m.bounds()[l].center;
    for (int i = 0; i < 3; ++i) posed.centres[l][i] = pose.R(i, 0) * c[0] + pose.R(i, 1) * c[1] + pose.R(i, 2) * c[2] + pose.t[i];
  }
}

// ---- SceneChecker: one posed state ----------------------------------------------------------------

namespace {

// An object as the exact tests take it: a box as the exact primitive it is (the environment
// keeps it as 12 triangles too, which the general queries use; mesh against box primitive measured
// faster here), everything else as the environment keeps it.
detail::ShapeRef object_shape(const CollisionObject& o) {
  if (o.shape.kind == ObjectShape::Kind::kBox) return {nullptr, nullptr, Primitive::box(o.shape.size)};
  return {o.mesh.get(), o.hull.get(), o.primitive};
}

}  // namespace

// An interval the proxies could not certify: is an exact distance at its midpoint worth its cost
// (some 10-30 us against 1-3 for a proxy test)? Not at a tolerance, where a failed interval is
// bisected until the tolerance takes it as colliding; at tolerance 0 once the growth is below the
// proxies' own error, `error` (half the level against an obstacle, the level for a self pair),
// where halving the interval no longer helps them; always without proxies.
// Is a finer level worth walking after the coarser ones failed, for this growth? Not when the
// growth exceeds its level: its spheres' error (half the level) is then small against the growth
// and it fails where they did, at the cost of a deeper walk. The coarsest always is.
bool SceneChecker::worth(const ProxyLevel* level, double growth) const {
  return level == proxies_.front() || level->level >= growth;
}

bool SceneChecker::exact_distance_pays(const Posed& s, double growth, double error) const {
  if (proxies_.empty()) return true;
  return !s.tolerant && growth <= error;
}

SceneChecker::Answer SceneChecker::pair_check(std::size_t p, const Posed& s) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const auto& bounds = m.bounds();
  const auto [a, b] = m.checked_pairs()[p];
  // Over an interval, the pair's proven clearance over the whole of it (a grid over the one or
  // two variables that move it) settles it with no growth at all.
  if (s.from != nullptr &&
      m.pair_clearance().lower_bound_over(p, s.from, s.to) > m.paddings()[a] + m.paddings()[b] + options_.min_clearance) {
    return Answer::kFree;
  }
  const double grow = s.pair_growth != nullptr ? s.pair_growth[p] : s.grow(a) + s.grow(b);
  const double pads = m.paddings()[a] + m.paddings()[b] + grow;
  const Vec3& ca = s.centres[a];
  const Vec3& cb = s.centres[b];
  const double margin = pose_margin(ca.norm() + cb.norm() + bounds[a].radius + bounds[b].radius);
  const double reach = bounds[a].radius + bounds[b].radius + pads + margin;
  if ((ca - cb).squaredNorm() > reach * reach) return Answer::kFree;
  if (m.pair_clearance().lower_bound(p, s.state) > pads) return Answer::kFree;
  const bool apart = std::any_of(proxies_.begin(), proxies_.end(), [&](const ProxyLevel* level) {
    return worth(level, grow) && !proxies_overlap(level->links[a], s.poses[a], level->links[b], s.poses[b], pads);
  });
  if (apart) return Answer::kFree;
  if (s.growth != nullptr) {
    // Proxies cannot tell within their level: the pair's exact distance at the midpoint can.
    if (!exact_distance_pays(s, grow, level_)) return s.no_free_radius();
    const double limit = grown_radius(pads) + margin;
    SelfCollisionResult r;
    const double d = checker_.pair_distance(a, b, s.poses, limit * (1 + 1e-9) + 1e-12, SelfCollisionRequest{}, r);
    if (d > limit) return Answer::kFree;
    s.note_free_radius(d - margin - (pads - grow) - options_.min_clearance, grow);
    return Answer::kNear;
  }
  if (s.tolerant && proxies_decide_self_) return Answer::kHit;
  SelfCollisionResult r;
  const SelfCollisionRequest request{s.tolerant ? options_.tolerance : 0.0};
  return checker_.pair_collides(a, b, s.poses, request, r) ? Answer::kHit : Answer::kFree;
}

bool SceneChecker::link_meets_object_exact(int link, const Transform& pose, int object, double tolerance) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const CollisionObject& o = env_->objects()[object];
  const detail::ShapeRef obstacle = object_shape(o);
  detail::PairRequest r;
  r.padding = m.paddings()[link];
  r.tolerance = tolerance;
  QueryStats stats;
  for (const LinkShape& shape : m.shapes()[link]) {
    if (detail::shapes_collide(m.ref(shape), pose * shape.origin, obstacle, o.pose, r, nullptr, stats)) return true;
  }
  return false;
}

double SceneChecker::link_object_distance(int link, const Transform& pose, int object, double limit) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const CollisionObject& o = env_->objects()[object];
  const detail::ShapeRef obstacle = object_shape(o);
  QueryStats stats;
  double best = limit * (1 + 1e-9) + 1e-12;
  for (const LinkShape& shape : m.shapes()[link]) {
    Vec3 wa, wb;
    best = std::min(best, detail::shapes_distance(m.ref(shape), pose * shape.origin, obstacle, o.pose, best, true, wa, wb, stats));
  }
  return best;
}

SceneChecker::Answer SceneChecker::link_objects_check(int l, const Posed& s) const {
  if (grid_.size() == 0) return Answer::kFree;
  const RobotCollisionModel& m = checker_.collision_model();
  {
    const double pad = m.paddings()[l] + s.grow(l);
    const Vec3& c = s.centres[l];
    const double r = m.bounds()[l].radius + pad;
    Answer answer = Answer::kFree;
    grid_.for_each_near(c, r, [&](int o) {
      if (answer != Answer::kFree || !grid_.ball_meets(o, c, r)) return;
      // A leaf whose centre lies deeper inside the object than the leaf's proven distance from
      // the link (its level's Hausdorff bound) proves a point of the link inside: a hit with no
      // exact test (the state itself only).
      bool proven = false;
      const bool apart = std::any_of(proxies_.begin(), proxies_.end(), [&](const ProxyLevel* level) {
        const LinkProxy& proxy = level->links[l];
        const double slack = proxy.hausdorff_bound() + proxy_pose_margin(proxy, s.poses[l]);
        return worth(level, s.grow(l)) && !proxy_meets_obstacle(proxy, s.poses[l], pad, [&](const Vec3& pc, double pr, bool leaf) {
          if (!grid_.ball_meets(o, pc, pr)) return false;
          if (leaf && s.growth == nullptr && !proven) proven = grid_.depth(o, pc) > slack;
          return true;
        });
      });
      if (apart) return;
      if (proven) {
        answer = Answer::kHit;
        return;
      }
      if (s.growth != nullptr) {
        // Within the proxies' level: the exact distance at the midpoint decides.
        if (!exact_distance_pays(s, s.grow(l), level_ / 2)) {
          answer = s.no_free_radius();
          return;
        }
        const double margin = pose_margin(c.norm() + r);
        const double limit = grown_radius(pad) + margin;
        const double d = link_object_distance(l, s.poses[l], o, limit);
        if (d > limit) return;
        s.note_free_radius(d - margin - m.paddings()[l] - options_.min_clearance, s.grow(l));
        answer = Answer::kNear;
      } else if ((s.tolerant && proxies_decide_objects_ && grid_.exact_ball_test(o)) ||
                 link_meets_object_exact(l, s.poses[l], o, s.tolerant ? options_.tolerance : 0.0)) {
        answer = Answer::kHit;
      }
    });
    return answer;
  }
}

SceneChecker::Answer SceneChecker::link_octree_check(int l, const Posed& s) const {
  const Octree& tree = env_->octree();
  if (tree.empty()) return Answer::kFree;
  const RobotCollisionModel& m = checker_.collision_model();
  const double pad = m.paddings()[l] + s.grow(l);
  const Vec3& c = s.centres[l];
  if (field_ && field_->lower_bound(c) > grown_radius(m.bounds()[l].radius + pad) + pose_margin(c.norm() + m.bounds()[l].radius)) {
    return Answer::kFree;
  }
  const bool apart = std::any_of(proxies_.begin(), proxies_.end(), [&](const ProxyLevel* level) {
    return worth(level, s.grow(l)) && !proxy_meets_obstacle(level->links[l], s.poses[l], pad, [&](const Vec3& pc, double pr, bool leaf) {
      if (field_ && field_->lower_bound(pc) > grown_radius(pr)) return false;
      if (!leaf) return true;
      // A grown ball (an interval) larger than a few voxels, or beyond the field's grid, counts as
      // meeting, to be split: the grid's scan of a ball grows with its volume (a 10 cm ball: a
      // thousand cells, 98 % of the demo arm's motion time), and the octree's walk too.
      if (s.growth != nullptr && (!field_ || pr > 4.0 * tree.resolution())) return true;
      if (field_) {
        if (const std::optional<bool> known = field_->ball_meets_occupied(pc, pr)) return *known;
      }
      if (s.growth != nullptr) return true;
      return !tree.occupied_in_sphere(pc, pr, true).empty();
    });
  });
  if (apart) return Answer::kFree;
  EnvironmentResult result;
  if (s.growth != nullptr) {
    if (!exact_distance_pays(s, s.grow(l), level_ / 2)) return s.no_free_radius();
    const double margin = pose_margin(c.norm() + m.bounds()[l].radius);
    const double limit = grown_radius(pad) + margin;
    // The distance field's bound from each leaf of the finest proxies first (the leaves hold the
    // link; within half the level and a voxel of the exact distance): the exact walk of the
    // octree only where that cannot clear the limit.
    double d = -1.0;
    if (field_ && !proxies_.empty()) {
      const LinkProxy& proxy = proxies_.back()->links[l];
      d = proxy_obstacle_distance(proxy, s.poses[l], limit * (1 + 1e-9) + 1e-12, [&](const Vec3& pc, double pr, double) {
        return std::max(0.0, field_->lower_bound(pc) - grown_radius(pr));
      });
      if (d > limit) return Answer::kFree;
    }
    d = std::max(d, checker_.link_octree_distance(l, s.poses[l], tree, limit * (1 + 1e-9) + 1e-12, true, result));
    if (d > limit) return Answer::kFree;
    s.note_free_radius(d - margin - m.paddings()[l] - options_.min_clearance, s.grow(l));
    return Answer::kNear;
  }
  if (s.tolerant && proxies_decide_objects_) return Answer::kHit;
  EnvironmentRequest request;
  request.tolerance = s.tolerant ? options_.tolerance : 0.0;
  request.contacts = false;
  return checker_.link_meets_octree(l, s.poses[l], tree, request, result) ? Answer::kHit : Answer::kFree;
}

// Component k: a checked self pair (k below the pair count), else the environment of one link.
SceneChecker::Answer SceneChecker::component_check(int k, const Posed& s) const {
  const int pairs = static_cast<int>(pair_rates_.size());
  if (k < pairs) return options_.self ? pair_check(static_cast<std::size_t>(k), s) : Answer::kFree;
  if (!options_.environment) return Answer::kFree;
  const int link = k - pairs;
  const Answer objects = link_objects_check(link, s);
  return objects != Answer::kFree ? objects : link_octree_check(link, s);
}

SceneChecker::Answer SceneChecker::check_posed(const Posed& s) const {
  for (const int k : components_) {
    if (const Answer a = component_check(k, s); a != Answer::kFree) return a;
  }
  return Answer::kFree;
}

// Marks (near[k] = 1) the components of `state` that the proxies cannot prove farther than the
// tolerance beyond their padding: each grown by the tolerance, a component apart is clear of it.
// (Not the tolerant state check: its "free" only says beyond padding.)
void SceneChecker::mark_within_tolerance(const double* state, std::vector<char>& near) const {
  thread_local Posed posed;
  thread_local std::vector<double> growth, pair_growth;
  growth.assign(checker_.collision_model().shapes().size(), options_.tolerance);
  pair_growth.assign(pair_rates_.size(), options_.tolerance);
  pose_links(state, posed);
  posed.growth = growth.data();
  posed.pair_growth = pair_growth.data();
  posed.from = posed.to = nullptr;
  posed.tolerant = true;  // no exact distances: the proxies decide or it is not clear
  posed.half = 0.0;
  for (const int k : components_) {
    if (component_check(k, posed) != Answer::kFree) near[k] = 1;
  }
}

bool SceneChecker::collides(const double* state) const {
  thread_local Posed posed;
  pose_links(state, posed);
  posed.growth = nullptr;
  posed.pair_growth = nullptr;
  posed.tolerant = options_.states_at_tolerance;
  return check_posed(posed) != Answer::kFree;
}

// ---- SceneChecker: motions ----------------------------------------------------------------------

namespace {

// How close (a fraction of the motion) the last valid state of a colliding motion must come to
// the collision found when the earliest one is asked for.
constexpr double kEarliestResolution = 1e-3;

// An interval of the motion and the components still pending over it (arena[first, first +
// count)): those its parent could not certify; the others are free over the parent, so over it.
struct Interval {
  double lo, hi;
  std::size_t first, count;
};

// The end of the certified intervals' run from 0 (they may overlap only at their ends).
double certified_prefix(std::vector<Interval> done) {
  std::sort(done.begin(), done.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
  double end = 0.0;
  for (const Interval& i : done) {
    if (i.lo > end) break;
    end = std::max(end, i.hi);
  }
  return end;
}

}  // namespace

template <class At>
SceneChecker::Step SceneChecker::check_interval(double lo, double hi, std::size_t first, std::size_t count, At&& at,
                                                const std::vector<char>& tolerant) const {
  thread_local Posed posed;
  Scratch& s = scratch();
  const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  s.from.assign(at(lo), at(lo) + s.state.size());
  s.to.assign(at(hi), at(hi) + s.state.size());
  pose_links(at(mid), posed);
  for (const int l : links_) {
    const double g = s.speed[l] * half;
    // min_clearance on top: a certified interval stays that far from every collision.
    s.growth[l] = g * (1.0 + 1e-9) + pose_margin(g) + options_.min_clearance;
  }
  for (std::size_t p = 0; p < s.pair_speed.size(); ++p) {
    const double g = s.pair_speed[p] * half;
    s.pair_growth[p] = g * (1.0 + 1e-9) + pose_margin(g) + options_.min_clearance;
  }
  posed.growth = s.growth.data();
  posed.pair_growth = s.pair_growth.data();
  posed.from = s.from.data();
  posed.to = s.to.data();
  // The pending components this interval cannot certify, appended to the arena for its halves;
  // `largest`: the most any of them can move (or close) over half the interval.
  posed.half = half;
  posed.free_radius = std::numeric_limits<double>::infinity();
  std::vector<int>& arena = s.pending;
  const std::size_t failing = arena.size();
  double largest = 0.0;
  bool all_tolerant = true;  // every failing component may take the tolerance's shortcut
  const int pairs = static_cast<int>(pair_rates_.size());
  for (std::size_t j = first; j < first + count; ++j) {
    const int k = arena[j];
    posed.tolerant = tolerant[k] != 0;
    if (component_check(k, posed) == Answer::kFree) continue;
    // Not certified: does it collide at the midpoint itself? (A planner's motions mostly
    // collide, and mostly where the intervals first fail: that ends the motion at once.)
    posed.growth = posed.pair_growth = nullptr;
    posed.from = posed.to = nullptr;
    const Answer now = component_check(k, posed);
    posed.growth = s.growth.data(), posed.pair_growth = s.pair_growth.data();
    posed.from = s.from.data(), posed.to = s.to.data();
    // (What follows it inherits the whole pending list: the rest was not looked at.)
    if (now != Answer::kFree) return {Step::kCollides, mid, first, count};
    arena.push_back(k);
    all_tolerant = all_tolerant && tolerant[k] != 0;
    largest = std::max(largest, (k < pairs ? s.pair_speed[k] : s.speed[k - pairs]) * half);
  }
  const std::size_t left = arena.size() - failing;
  if (left == 0) return {Step::kCertified};
  // Proxies within the level of the links, grown by at most `largest`: a failed interval puts a
  // link within level + 2 largest (a self pair) of a collision at its midpoint.
  if (all_tolerant && level_ + 2.0 * (largest + options_.min_clearance) <= options_.tolerance) {
    return {Step::kCollides, mid, failing, left};
  }
  // Growth below the level is tested by exact distances: a failure with the motion's own growth
  // within min_clearance puts a pair within padding + 2 min_clearance at the midpoint (counted as
  // colliding, as advancement counts one within min_clearance).
  if (2.0 * largest <= options_.min_clearance && (largest <= level_ / 2 || proxies_.empty())) {
    return {Step::kCollides, mid, failing, left};
  }
  // Every component that failed did so on an exact distance at the midpoint: each is free for
  // as long as it cannot have closed that gap, the smallest of which frees a middle stretch.
  Step split{Step::kSplit, -1.0, failing, left};
  if (std::isfinite(posed.free_radius) && posed.free_radius > 0.0) {
    split.free_lo = std::max(lo, mid - posed.free_radius);
    split.free_hi = std::min(hi, mid + posed.free_radius);
  }
  return split;
}

// Per link and per self pair, how fast they can move (close) per unit fraction of this segment.
void SceneChecker::motion_speeds(const double* start, const double* goal) const {
  Scratch& s = scratch();
  const RobotCollisionModel& m = checker_.collision_model();
  s.speed.assign(m.shapes().size(), 0.0);
  for (const int l : links_) s.speed[l] = checker_.link_speed(l, start, goal);
  s.growth.assign(m.shapes().size(), 0.0);
  s.pair_speed.assign(pair_rates_.size(), 0.0);
  s.pair_growth.assign(pair_rates_.size(), 0.0);
  for (std::size_t p = 0; p < pair_rates_.size(); ++p) {
    const auto [a, b] = m.checked_pairs()[p];
    if (!pair_rates_[p].relative) {
      s.pair_speed[p] = s.speed[a] + s.speed[b];
      continue;
    }
    for (const auto& [v, w] : pair_rates_[p].weights) s.pair_speed[p] += w * std::abs(goal[v] - start[v]);
  }
}

MotionResult SceneChecker::check_motion(const double* start, const double* goal, bool earliest) const {
  const std::size_t n = checker_.model().variable_count();
  for (std::size_t j = 0; j < n; ++j) {
    if (!std::isfinite(start[j]) || !std::isfinite(goal[j])) {
      throw std::invalid_argument("motion check: " + checker_.model().variable_names()[j] + " is not finite");
    }
  }
  MotionResult result;
  Scratch& s = scratch();
  s.state.resize(n);
  auto at = [&](double f) {
    for (std::size_t j = 0; j < n; ++j) s.state[j] = f >= 1.0 ? goal[j] : start[j] + f * (goal[j] - start[j]);
    return s.state.data();
  };
  // The ends first (a planner's goal state is often the colliding one); the start's collision is
  // the earliest there is.
  result.states_checked = 2;
  if (collides(at(0.0))) {
    result.colliding_fraction = 0.0;
    result.certified = true;
    return result;
  }
  double found = collides(at(1.0)) ? 1.0 : -1.0;  // the earliest collision known
  if (found >= 0.0 && !earliest) {
    result.colliding_fraction = found;
    result.certified = true;
    return result;
  }
  // At a tolerance, a motion may count as colliding where a component (a self pair, a link against
  // the environment) comes within the tolerance, unless that component already is at one of its
  // ends: a planner must be able to leave a state it accepted. (And only with a level of at most
  // half the tolerance: the rest is the room an interval's growth needs before the tolerance
  // can take the interval as colliding.)
  std::vector<char>& tolerant = s.tolerant;
  tolerant.assign(pair_rates_.size() + checker_.collision_model().shapes().size(), 0);
  if (options_.tolerance > 0.0 && !proxies_.empty() && level_ <= options_.tolerance / 2) {
    std::vector<char>& near = s.near;
    near.assign(tolerant.size(), 0);
    mark_within_tolerance(start, near);
    mark_within_tolerance(goal, near);
    for (const int k : components_) tolerant[k] = near[k] ? 0 : 1;
  }
  motion_speeds(start, goal);
  std::vector<int>& arena = s.pending;
  arena.assign(components_.begin(), components_.end());
  std::vector<Interval> done;
  std::deque<Interval> todo{{0.0, 1.0, 0, components_.size()}};
  while (!todo.empty()) {
    const Interval i = earliest ? todo.back() : todo.front();
    earliest ? todo.pop_back() : todo.pop_front();
    // Beyond a collision already found, or (the earliest one) within a thousandth of the motion
    // before it: the last valid state is then that close to it, which is all a planner needs.
    if (found >= 0.0 && i.lo >= found - (earliest ? kEarliestResolution : 0.0)) continue;
    if (++result.states_checked > options_.max_intervals) {
      result.message = "not certified after " + std::to_string(options_.max_intervals) + " intervals";
      result.last_valid_fraction = certified_prefix(done);
      return result;
    }
    const Step step = check_interval(i.lo, i.hi, i.first, i.count, at, tolerant);
    if (step.outcome == Step::kCertified) {
      done.push_back(i);
    } else if (step.outcome == Step::kCollides) {
      found = found < 0.0 ? step.at : std::min(found, step.at);
      if (!earliest) break;
      if (step.at > i.lo) todo.push_back({i.lo, step.at, step.first, step.count});
    } else {
      // The halves, less a middle stretch the exact distances freed (free_lo, free_hi).
      const double mid = 0.5 * (i.lo + i.hi);
      const double cut_lo = step.free_hi > step.free_lo ? step.free_lo : mid;
      const double cut_hi = step.free_hi > step.free_lo ? step.free_hi : mid;
      if (cut_hi > cut_lo) done.push_back({cut_lo, cut_hi, 0, 0});
      const Interval left{i.lo, cut_lo, step.first, step.count}, right{cut_hi, i.hi, step.first, step.count};
      for (const Interval& half : earliest ? std::array<Interval, 2>{right, left} : std::array<Interval, 2>{left, right}) {
        if (half.hi > half.lo) todo.push_back(half);
      }
    }
  }
  result.certified = true;
  if (found >= 0.0) {
    result.colliding_fraction = found;
    result.last_valid_fraction = certified_prefix(done);
    return result;
  }
  result.valid = true;
  result.last_valid_fraction = 1.0;
  return result;
}

}  // namespace bvh_collision
