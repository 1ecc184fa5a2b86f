// SceneChecker: one state and one motion against one environment snapshot (scene_checker.h).
#include "bvh_collision/query/scene_checker.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/split_column.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"
#include "scene_memory.h"

namespace bvh_collision {

// ---- SceneChecker: set-up ----------------------------------------------------------------------

namespace {

// How the tolerance policy lets proxy levels serve a certified motion's intervals.
ProxyUse motion_use(double tolerance) {
  ToleranceQuestion question{tolerance, Counterpart::kLink};
  question.motion = true;
  return proxy_use(question);
}

// The levels tests go through, coarsest first, down to the finest that serves `tolerance` as a
// certified motion's (narrowphase/tolerance_policy.h; states use the same): at a tolerance the
// coarsest level up to it, exact: every level.
std::vector<const ProxyLevel*> levels_for(const RobotAccelerators& m, double tolerance) {
  const ProxyUse use = motion_use(tolerance);
  const ProxyLevel* finest = m.proxies_for(use.decide_up_to);
  std::vector<const ProxyLevel*> out;
  for (const ProxyLevel& p : m.proxy_levels()) {
    if (finest == nullptr || p.level >= finest->level) out.push_back(&p);
  }
  std::sort(out.begin(), out.end(), [](const ProxyLevel* a, const ProxyLevel* b) { return a->level > b->level; });
  return out;
}

std::atomic<std::uint64_t> next_serial{1};

}  // namespace

SceneChecker::SceneChecker(CollisionChecker checker, std::shared_ptr<const Environment> environment,
                           const SceneCheckOptions& options)
    : checker_(std::move(checker)), env_(std::move(environment)), serial_(next_serial++), options_(options) {
  if (!env_) throw std::invalid_argument("scene checker: no environment");
  if (!checker_.carries(*env_)) checker_ = checker_.carrying(*env_);  // what the robot carries moves with it
  if (!is_rigid(options.root_pose)) throw std::invalid_argument("scene checker: the root pose is not a finite rigid transform");
  if (!std::isfinite(options.tolerance) || options.tolerance < 0.0) throw std::invalid_argument("scene checker: tolerance must be finite and >= 0");
  const RobotCollisionModel& m = checker_.collision_model();
  proxies_ = levels_for(checker_.accelerators(), options.tolerance);
  level_ = proxies_.empty() ? 0.0 : proxies_.back()->level;
  pair_exact_growth_ = std::max(level_, options.pair_exact_growth >= 0.0 ? options.pair_exact_growth
                                                                          : checker_.accelerators().pair_exact_growth());
  proxies_decide_self_ = !proxies_.empty() && proxy_error(level_, Counterpart::kLink) <= options.tolerance;
  proxies_decide_objects_ = !proxies_.empty() && proxy_error(level_, Counterpart::kObject) <= options.tolerance;
  // The tolerance answers a component's midpoint where it is clear of it at both ends (a level
  // that fits decides there); a failing interval is taken as colliding only where the level's error
  // leaves room for its growth (interval_within_tolerance: at a level of the tolerance itself,
  // against an obstacle only).
  tolerance_asked_ = !proxies_.empty() && level_ <= motion_use(options.tolerance).decide_up_to;
  double reach = 0.0;
  for (std::size_t l = 0; l < m.shapes().size(); ++l) {
    if (m.shapes()[l].empty()) continue;
    links_.push_back(static_cast<int>(l));
    reach = std::max(reach, m.bounds()[l].radius + m.paddings()[l]);
  }
  relative_pair_rates();
  interval_chains();
  for (const auto& [a, b] : m.checked_pairs()) {
    pair_balls_.push_back({a, b, m.bounds()[a].radius + m.bounds()[b].radius + m.paddings()[a] + m.paddings()[b]});
  }
  link_reach_.assign(m.shapes().size(), 0.0);
  for (const int l : links_) {
    largest_radius_ = std::max(largest_radius_, m.bounds()[l].radius);
    link_reach_[l] = m.bounds()[l].radius + m.paddings()[l];
  }
  octree_ = !env_->octree().empty();
  root_at_origin_ = options.root_pose.R == Mat3::Identity() && options.root_pose.t == Vec3::Zero();
  // Each link's environment first, the links farthest down the chain first, then the self pairs:
  // a planner's states and motions in a scene mostly collide with objects, and with the hand
  // and forearm first (an interval whose midpoint collides stops there): fewer instructions than
  // self pairs first, the same answers (docs/performance.md).
  for (auto l = links_.rbegin(); l != links_.rend(); ++l) {
    if (options.environment) components_.push_back(static_cast<int>(pair_rates_.size()) + *l);
  }
  for (std::size_t p = 0; p < pair_rates_.size() && options.self; ++p) components_.push_back(static_cast<int>(p));
  if (options.environment && !env_->objects().empty()) {
    // Cells of 10 cm over the reach around the root; queries up to the largest link ball plus
    // 5 cm of growth use the cell's list.
    const Vec3 around = Vec3::Constant(checker_.reach() + 0.1);
    grid_ = ObjectGrid(env_->objects(), options.root_pose.t - around, options.root_pose.t + around, reach + 0.05, 0.1);
    if (!env_->allowed_collisions().empty()) {  // per (link, object): allowed to touch, so not checked
      allowed_.assign(m.shapes().size() * env_->objects().size(), 0);
      for (const int l : links_) {
        for (std::size_t o = 0; o < env_->objects().size(); ++o) allowed_[l * env_->objects().size() + o] = env_->object_allowed(checker_.model().links()[l].name, o);
      }
    }
  }
  if (options.environment && !env_->octree().empty()) {
    field_ = checker_.kept_distance_field(*env_, options.root_pose);
    if (!field_) field_ = checker_.prepare_distance_field(*env_, options.root_pose);
  }
}

void SceneChecker::pose_links(const double* state, Posed& posed) const {
  const RobotCollisionModel& m = checker_.collision_model();
  posed.state = state;
  m.kinematics().compute(state, posed.poses);
  posed.centres.resize(posed.poses.size());
  posed.centre_norms.resize(posed.poses.size());
  if (!root_at_origin_) {  // every computed link (the joints' axes too) into the environment's frame
    for (const KinematicsPlan::Step& step : m.kinematics().step_list()) posed.poses[step.link] = options_.root_pose * posed.poses[step.link];
    posed.poses[m.kinematics().root()] = options_.root_pose * posed.poses[m.kinematics().root()];
  }
  double largest = 0.0;
  for (const int l : links_) {
    Vec3& c = posed.centres[l];
    transform_point(posed.poses[l], m.bounds()[l].center.data(), c.data());
    posed.centre_norms[l] = std::sqrt((c[0] * c[0] + c[1] * c[1]) + c[2] * c[2]);  // as Vec3::norm()
    largest = std::max(largest, posed.centre_norms[l]);
  }
  posed.largest_norm = largest;
}

// ---- SceneChecker: one posed state ----------------------------------------------------------------

// Is a finer level worth walking after the coarser ones failed, for this growth? Not when the
// growth exceeds its level: its spheres' error (half the level) is then small against the growth
// and it fails where they did, at the cost of a deeper walk. The coarsest always is.
bool SceneChecker::worth(const ProxyLevel* level, double growth) const {
  return level == proxies_.front() || level->level >= growth;
}

// The one level a link walks against an object, or a self pair walks: the finest worth walking
// for the growth. A link that meets an object at the coarser levels mostly meets it at the finest
// too, and a link the object grid offers an object is mostly near it (fewer instructions than
// walking each level from the coarsest: docs/performance.md). Null without levels.
const ProxyLevel* SceneChecker::walked_level(double growth) const {
  const auto finest = std::find_if(proxies_.rbegin(), proxies_.rend(), [&](const ProxyLevel* level) { return worth(level, growth); });
  return finest == proxies_.rend() ? nullptr : *finest;
}

// An interval the proxies could not certify: is an exact distance at its midpoint worth its cost?
// Not at a tolerance, where a failed interval is bisected until the tolerance takes it as
// colliding; at tolerance 0 once the growth is at most `error`: against an obstacle the proxies'
// own error (half the finest level), where halving the interval no longer helps them; for a self
// pair the growth the robot's timing chose (pair_exact_growth_, at least the finest level:
// query/motion_calibration.h); always without proxies.
bool SceneChecker::exact_distance_pays(const Posed& s, double growth, double error) const {
  if (proxies_.empty()) return true;
  return growth <= error && !s.tolerant();
}

bool SceneChecker::pair_balls_apart(std::size_t p, const Posed& s) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const auto& bounds = m.bounds();
  const auto [a, b] = m.checked_pairs()[p];
  const double grow = s.pair_growth != nullptr ? s.pair_growth[p] : s.grow(a) + s.grow(b);
  const double pads = m.paddings()[a] + m.paddings()[b] + grow;
  const double margin = pose_margin(s.centre_norms[a] + s.centre_norms[b] + bounds[a].radius + bounds[b].radius);
  const double reach = bounds[a].radius + bounds[b].radius + pads + margin;
  return (s.centres[a] - s.centres[b]).squaredNorm() > reach * reach;
}

SceneChecker::Answer SceneChecker::pair_check(std::size_t p, const Posed& s) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const auto& bounds = m.bounds();
  const int a = m.checked_pairs()[p].first, b = m.checked_pairs()[p].second;  // (named, not bound: a lambda below takes them)
  // Over an interval, the pair's proven clearance over the whole of it (a grid over the one or
  // two variables that move it) settles it with no growth at all.
  if (s.from != nullptr &&
      checker_.accelerators().pair_clearance().clear_over(p, s.from, s.to, m.paddings()[a] + m.paddings()[b] + options_.min_clearance)) {
    return Answer::kFree;
  }
  if (!s.balls_sieved && pair_balls_apart(p, s)) return Answer::kFree;
  const double grow = s.pair_growth != nullptr ? s.pair_growth[p] : s.grow(a) + s.grow(b);
  const double pads = m.paddings()[a] + m.paddings()[b] + grow;
  const double margin = pose_margin(s.centre_norms[a] + s.centre_norms[b] + bounds[a].radius + bounds[b].radius);
  const PairClearance& clearance = checker_.accelerators().pair_clearance();
  if (clearance.has_grid(p) && clearance.lower_bound(p, s.state) > pads) return Answer::kFree;
  // Past the balls (and a grid, which puts the pair within a few centimetres when it cannot bound
  // it), one level's spheres: the finest worth walking (walked_level).
  const ProxyLevel* walked = walked_level(grow);
  if (walked != nullptr) {
    if (s.witnesses.size() != m.checked_pairs().size()) s.witnesses.assign(m.checked_pairs().size(), ProxyWitness{});
    if (!proxies_overlap(walked->links[a], s.poses[a], walked->links[b], s.poses[b], pads, &s.witnesses[p])) return Answer::kFree;
  }
  if (s.growth != nullptr) {
    // Beside a link the motion does not move relative to it but by one joint, the pair's clearance
    // along that joint, proven once (held_pair_clearance.h).
    if (s.from != nullptr && held_pair_clear(p, s.from, s.to)) return Answer::kFree;
    // Proxies cannot tell within their level: the pair's exact distance at the midpoint can.
    if (!exact_distance_pays(s, grow, pair_exact_growth_)) return s.no_free_radius();
    const double limit = grown_radius(pads) + margin;
    Vec3 wa, wb;
    QueryStats stats;
    const double d = compounds_distance(m.compound(a), s.poses[a], m.compound(b), s.poses[b], query_limit_above(limit), true,
                                        wa, wb, stats);
    if (d > limit) return Answer::kFree;
    s.note_free_radius(d - margin - (pads - grow) - s.clearance, grow);
    return Answer::kNear;
  }
  if (proxies_decide_self_ && s.tolerant()) return Answer::kHit;
  PairRequest request;
  request.padding = m.paddings()[a] + m.paddings()[b];
  request.tolerance = s.tolerant() ? options_.tolerance : 0.0;
  QueryStats stats;
  return compounds_collide(m.compound(a), s.poses[a], m.compound(b), s.poses[b], request, nullptr, stats) ? Answer::kHit
                                                                                                          : Answer::kFree;
}

bool SceneChecker::link_meets_object_exact(int link, const Transform& pose, int object, double tolerance) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const CollisionObject& o = env_->objects()[object];
  const ShapeRef obstacle = exact_shape_of(o);
  PairRequest r;
  r.padding = m.paddings()[link];
  r.tolerance = tolerance;
  QueryStats stats;
  return compound_collides(m.compound(link), pose, obstacle, o.pose, r, nullptr, stats);
}

// Asked within a slack (a hundredth of the limit, at most 10 um) and returned less it: a lower
// bound, all a motion needs of it (the stretch it frees shrinks by about the slack over the gap).
// Exact to the last digit, GJK creeps for dozens of steps towards a curved obstacle (the cage's
// bars) and refines for hundreds more, most of the work of a slow motion.
double SceneChecker::link_object_distance(int link, const Transform& pose, int object, double limit) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const CollisionObject& o = env_->objects()[object];
  const ShapeRef obstacle = exact_shape_of(o);
  QueryStats stats;
  const double slack = std::min(1e-5, 0.01 * limit);
  Vec3 wa, wb;
  const double best = compound_distance(m.compound(link), pose, obstacle, o.pose, query_limit_above(limit) + slack, true,
                                        wa, wb, stats, slack);
  return best - slack;
}

SceneChecker::Answer SceneChecker::link_objects_check(int l, const Posed& s) const {
  if (grid_.size() == 0) return Answer::kFree;
  const RobotCollisionModel& m = checker_.collision_model();
  {
    const double pad = m.paddings()[l] + s.grow(l);
    const Vec3& c = s.centres[l];
    const double r = m.bounds()[l].radius + pad;
    Answer answer = Answer::kFree;
    // (Over an interval, an object the link failed on by its exact distance leaves the others to
    // look at: the stretch that distance frees holds for that object only, and each of the others
    // must free it too. Any other failure frees nothing: the walk stops there.)
    auto done = [&] { return answer == Answer::kHit || (answer == Answer::kNear && !(s.free_radius > 0.0)); };
    const ProxyLevel* walked = walked_level(s.grow(l));
    const std::size_t objects = env_->objects().size();
    if (s.object_witnesses.size() != m.bounds().size() * objects) s.object_witnesses.assign(m.bounds().size() * objects, -1);
    grid_.for_each_near(c, r, [&](int o) {
      if (done()) {
        s.gaps = 0;  // (an object left unexamined: the midpoint's own check must look)
        return;
      }
      if ((!allowed_.empty() && allowed_[l * env_->objects().size() + o]) || !grid_.ball_meets(o, c, r)) return;
      // A leaf whose centre lies deeper inside the object than the leaf's proven distance from
      // the link (its level's Hausdorff bound) proves a point of the link inside: a hit with no
      // exact test (the state itself only).
      // A primitive's spheres are carried into its frame at once (one transform a sphere, not
      // two).
      bool proven = false;
      const bool local = grid_.exact_ball_test(o);
      const Transform in_object = local ? grid_.to_local(o) * s.poses[l] : Transform();
      std::int32_t* witness = &s.object_witnesses[l * objects + o];
      const bool apart = walked != nullptr && [&](const ProxyLevel* level) {
        const LinkProxy& proxy = level->links[l];
        const double margin = proxy_pose_margin(proxy, s.poses[l]);
        const double slack = proxy.hausdorff_bound() + margin;
        if (local) {
          return !proxy_meets_obstacle(proxy, in_object, pad, [&](const Vec3& p, double pr, bool leaf) {
            if (!grid_.local_ball_meets(o, p, pr, margin)) return false;
            if (leaf && s.growth == nullptr && !proven) proven = grid_.local_depth(o, p, margin) > slack;
            return true;
          }, witness);
        }
        return !proxy_meets_obstacle(proxy, s.poses[l], pad, [&](const Vec3& pc, double pr, bool leaf) {
          if (!grid_.ball_meets(o, pc, pr)) return false;
          if (leaf && s.growth == nullptr && !proven) proven = grid_.depth(o, pc) > slack;
          return true;
        }, witness);
      }(walked);
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
        s.note_free_radius(d - margin - m.paddings()[l] - s.clearance, s.grow(l));
        answer = Answer::kNear;
      } else if ((proxies_decide_objects_ && grid_.exact_ball_test(o) && s.tolerant()) ||
                 link_meets_object_exact(l, s.poses[l], o, s.tolerant() ? options_.tolerance : 0.0)) {
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
  if (field_ && field_->lower_bound(c) > grown_radius(m.bounds()[l].radius + pad) + pose_margin(s.centre_norms[l] + m.bounds()[l].radius)) {
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
  QueryStats stats;
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
      d = proxy_obstacle_distance(proxy, s.poses[l], query_limit_above(limit), [&](const Vec3& pc, double pr, double) {
        return std::max(0.0, field_->lower_bound(pc) - grown_radius(pr));
      });
      if (d > limit) return Answer::kFree;
    }
    d = std::max(d, compound_octree_distance(m.compound(l), s.poses[l], tree, true, query_limit_above(limit), stats).distance);
    if (d > limit) return Answer::kFree;
    s.note_free_radius(d - margin - m.paddings()[l] - s.clearance, s.grow(l));
    return Answer::kNear;
  }
  if (proxies_decide_objects_ && s.tolerant()) return Answer::kHit;
  PairRequest request;
  request.padding = m.paddings()[l];
  request.tolerance = s.tolerant() ? options_.tolerance : 0.0;
  return compound_meets_octree(m.compound(l), s.poses[l], tree, request, nullptr, stats) ? Answer::kHit : Answer::kFree;
}

// Component k: a checked self pair (k below the pair count), else the environment of one link.
SceneChecker::Answer SceneChecker::component_check(int k, const Posed& s) const {
  const int pairs = static_cast<int>(pair_rates_.size());
  if (k < pairs) return options_.self ? pair_check(static_cast<std::size_t>(k), s) : Answer::kFree;
  if (!options_.environment) return Answer::kFree;
  const int link = k - pairs;
  const Answer objects = link_objects_check(link, s);
  if (objects == Answer::kHit || !octree_) return objects;
  // Failed on exact distances to objects (free_radius > 0): the octree must free the stretch too.
  if (objects == Answer::kNear && !(s.free_radius > 0.0)) {
    s.gaps = 0;  // (the octree left unexamined)
    return objects;
  }
  const Answer tree = link_octree_check(link, s);
  return tree == Answer::kFree ? objects : tree == Answer::kHit ? tree : Answer::kNear;
}

SceneChecker::Answer SceneChecker::check_posed(const Posed& s) const {
  if (s.growth == nullptr && s.pair_growth == nullptr) return check_still(s);
  const int pairs = static_cast<int>(pair_rates_.size());
  for (const int k : components_) {
    // A link whose grown ball the object grid's cell proves clear, with no octree: the first
    // test of link_objects_check, without the call.
    if (k >= pairs && !octree_ && grid_.clear(s.centres[k - pairs], link_reach_[k - pairs] + s.grow(k - pairs))) continue;
    if (const Answer a = component_check(k, s); a != Answer::kFree) return a;
  }
  return Answer::kFree;
}

// A state's components in checking order, sieved 64 at a time by their first tests, as bits
// with no call and no branch a component: a link whose grown ball the object grid's cell proves
// clear of every object, with no octree, is free (link_objects_check's first test), and so is a
// self pair whose bounding balls are apart (pair_check's). Most of a planner's free state ends
// here (as a loop of tests and branches it cost several times as much).
// The links' blocks are called before the pairs' are sieved: a colliding state mostly meets an
// object.
SceneChecker::Answer SceneChecker::check_still(const Posed& s) const {
  const auto sieve = [&](std::size_t lo, std::size_t hi, auto&& may_meet) {
    for (std::size_t first = lo; first < hi; first += 64) {
      const std::size_t end = std::min(hi, first + 64);
      std::uint64_t call = 0;
      for (std::size_t i = first; i < end; ++i) call |= static_cast<std::uint64_t>(may_meet(components_[i])) << (i - first);
      for (; call != 0; call &= call - 1) {
        if (const Answer a = component_check(components_[first + __builtin_ctzll(call)], s); a != Answer::kFree) return a;
      }
    }
    return Answer::kFree;
  };
  const int pairs = static_cast<int>(pair_rates_.size());
  const std::size_t link_end = options_.environment ? links_.size() : 0;  // components_: links, then pairs
  const Answer links = sieve(0, link_end, [&](int k) { return octree_ || !grid_.clear(s.centres[k - pairs], link_reach_[k - pairs]); });
  if (links != Answer::kFree) return links;
  // pair_check's margin for any pair (its links' centre norms and radii at their largest): a
  // wider margin only widens the test.
  const double margin = pose_margin(2.0 * (s.largest_norm + largest_radius_));
  s.balls_sieved = true;
  const Answer pairs_answer = sieve(link_end, components_.size(), [&](int k) {
    const PairBalls& p = pair_balls_[k];
    const double reach = p.reach + margin;
    return !((s.centres[p.a] - s.centres[p.b]).squaredNorm() > reach * reach);
  });
  s.balls_sieved = false;
  return pairs_answer;
}

bool SceneChecker::collides(const double* state) const {
  checker_.require_finite_state(state, "state check");
  StateScratch& scratch = state_scratch();
  const std::size_t slot = state_slot(state);  // (hashed once)
  if (known_free(scratch, state, slot)) return false;
  Posed& posed = scratch.posed;
  pose_links(state, posed);
  posed.growth = nullptr;
  posed.pair_growth = nullptr;
  posed.tolerant_flag = options_.states_at_tolerance;
  posed.ends = nullptr;
  if (check_posed(posed) != Answer::kFree) return true;
  remember_free(scratch, state, slot);
  return false;
}

}  // namespace bvh_collision
