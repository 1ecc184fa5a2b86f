// SceneChecker's certified motions: intervals checked at once, bisected, settled by exact
// distances below the proxies' error (query/scene_checker.h).
#include "bvh_collision/query/scene_checker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/split_column.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"
#include "motion_scratch.h"

namespace bvh_collision {

namespace {

using scene_motion::Interval;

// How close (a fraction of the motion) the last valid state of a colliding motion must come to
// the collision found when the earliest one is asked for.
constexpr double kEarliestResolution = 1e-3;

// A motion whose whole interval fails, grown by more than this, is cut into pieces grown by about
// this much rather than halved: a long motion's halves and quarters fail too, each costing a grown
// check of every pending component and a midpoint check. The size was chosen on the planning
// benchmark's motions (docs/performance.md).
constexpr double kFirstPieceGrowth = 0.2;

// The order in which the m pieces of a motion are checked: breadth first (a boolean answer), the
// middle of each run of pieces first, so that the midpoints checked early are spread along the
// motion as bisection spreads them (a colliding motion meets its collision as soon); depth first
// (the earliest collision), pushed right to left, so the leftmost piece is taken first.
// (Into `order`; `runs` is working memory.)
void spread_order(int m, bool earliest, std::vector<int>& order, std::vector<std::pair<int, int>>& runs) {
  order.clear();
  if (earliest) {
    for (int k = m - 1; k >= 0; --k) order.push_back(k);
    return;
  }
  runs.assign(1, {0, m});  // [lo, hi) runs of pieces not yet ordered
  for (std::size_t r = 0; r < runs.size(); ++r) {
    const auto [lo, hi] = runs[r];
    if (lo >= hi) continue;
    const int mid = (lo + hi) / 2;
    order.push_back(mid);
    runs.emplace_back(lo, mid);
    runs.emplace_back(mid + 1, hi);
  }
}

// The end of the certified intervals' run from 0 (they may overlap only at their ends).
double certified_prefix(std::vector<Interval>& done) {
  std::sort(done.begin(), done.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
  double end = 0.0;
  for (const Interval& i : done) {
    if (i.lo > end) break;
    end = std::max(end, i.hi);
  }
  return end;
}

}  // namespace

// (Not inlined: a caller keeps the reference it returns, where a thread_local named in a loop
// costs a call to __tls_get_addr at every use after a call, in a shared library.)
[[gnu::noinline]] SceneChecker::MotionScratch& SceneChecker::motion_scratch() {
  thread_local MotionScratch s;
  return s;
}

template <class At>
SceneChecker::Step SceneChecker::check_interval(double lo, double hi, std::size_t first, std::size_t count, At&& at,
                                                Posed* ends) const {
  MotionScratch& s = motion_scratch();
  Posed& posed = s.midpoint;
  const double mid = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  // (at() writes the motion's moving variables only: the buffers hold the others' values.)
  at(lo, s.from.data());
  at(hi, s.to.data());
  pose_moving_links(at(mid, s.state.data()), posed, s.pending.data() + first, count);
  std::vector<int>& arena = s.pending;
  const int pairs = static_cast<int>(pair_rates_.size());
  // The margin of a pair's bounding-ball test is any pair's (the largest centre norm and
  // radius): wider only widens the test.
  const double margin = pose_margin(2.0 * (posed.largest_norm + largest_radius_));
  // A pending component that its motion's chain-length rate already certifies over the interval
  // needs no speed from the midpoint's levers (chain_speed, a good part of an interval's work):
  // a link whose ball, grown by that rate, the object grid's cell proves clear (no octree), a
  // self pair whose bounding balls, so grown, are apart. The levers' rate is never above it
  // (chain_speed's cap), so these would pass with it too: the same components certified.
  std::vector<int>& near = s.near;
  near.clear();
  for (std::size_t j = first; j < first + count; ++j) {
    const int k = arena[j];
    const double cap = grown_growth((k < pairs ? s.pair_speed[k] : s.speed[k - pairs]) * half) + options_.min_clearance;
    if (k >= pairs) {
      if (!octree_ && grid_.clear(posed.centres[k - pairs], link_reach_[k - pairs] + cap)) continue;
    } else {
      const PairBalls& p = pair_balls_[k];
      const double reach = p.reach + cap + margin;
      if ((posed.centres[p.a] - posed.centres[p.b]).squaredNorm() > reach * reach) continue;
    }
    near.push_back(k);
  }
  IntervalRates rates{s.delta.data(),          s.chain_delta.data(),         s.turning_total.data(), s.speed.data(),
                      s.pair_speed.data(),     s.interval_speed.data(),      s.interval_pair_speed.data(),
                      &s.sums,                 &s.axes,                      &s.turning_moving,
                      &s.chain_reads,          &s.read_links};
  interval_speeds(posed, half, near.data(), near.size(), rates);
  // Each pending component's growth; a self pair whose bounding balls, so grown, are apart is
  // certified at once (most of a two-arm robot's pairs end here: one pass, no call a pair).
  std::vector<int>& live = s.live;
  live.clear();
  for (const int k : near) {
    const double g = (k < pairs ? s.interval_pair_speed[k] : s.interval_speed[k - pairs]) * half;
    // The component's floor on top (min_clearance, or less for an end closer than that:
    // end_clearance_floor): a certified interval stays that far from every collision.
    const double grown = grown_growth(g) + (s.floors_lowered ? s.floor[k] : options_.min_clearance);
    if (k >= pairs) {
      s.growth[k - pairs] = grown;
    } else {
      s.pair_growth[k] = grown;
      const PairBalls& p = pair_balls_[k];
      const double reach = p.reach + grown + margin;
      if ((posed.centres[p.a] - posed.centres[p.b]).squaredNorm() > reach * reach) continue;
    }
    live.push_back(k);
  }
  posed.growth = s.growth.data();
  posed.pair_growth = s.pair_growth.data();
  posed.from = s.from.data();
  posed.to = s.to.data();
  // The pending components this interval cannot certify, appended to the arena for its halves;
  // `largest`: the most any of them can move (or close) over half the interval.
  posed.half = half;
  posed.free_radius = std::numeric_limits<double>::infinity();
  const std::size_t failing = arena.size();
  double largest = 0.0;
  posed.checker = this;
  posed.ends = tolerance_asked_ ? ends : nullptr;
  posed.tolerant_flag = false;
  for (const int k : live) {
    posed.component = k;
    posed.clearance = s.floors_lowered ? s.floor[k] : options_.min_clearance;
    // Over the whole motion, a component grown by more than a piece's growth is not walked: so
    // grown it meets what is near it (its walk goes deep before it fails) and the pieces will
    // check it again. Its midpoint check still runs. It has no exact distance, so it frees no
    // stretch around the midpoint: another component's distance would free it there too (test
    // AStretchFreedByOneLinkDoesNotFreeAFasterOne). (The same answers, fewer instructions; the
    // same skip in every interval costs more: docs/performance.md.)
    const bool hopeless = hi - lo == 1.0 && (k < pairs ? s.pair_growth[k] : s.growth[k - pairs]) > kFirstPieceGrowth;
    posed.clear_gaps();
    if (hopeless) {
      posed.no_free_radius();
    } else {
      posed.balls_sieved = true;  // (live: its pairs' balls, grown, were not apart)
      const Answer over = component_check(k, posed);
      posed.balls_sieved = false;
      if (over == Answer::kFree) continue;
    }
    // Not certified: does it collide at the midpoint itself? (A planner's motions mostly
    // collide, and mostly where the intervals first fail: that ends the motion at once.) Not
    // where it failed only on exact distances there beyond its padding: those were taken at the
    // exact answer (with proxies, exact_distance_pays takes none where the tolerance may count),
    // which the midpoint's own check would give again.
    if (!(posed.gaps == 1 && !proxies_.empty())) {
      posed.growth = posed.pair_growth = nullptr;
      posed.from = posed.to = nullptr;
      const Answer now = component_check(k, posed);
      posed.growth = s.growth.data(), posed.pair_growth = s.pair_growth.data();
      posed.from = s.from.data(), posed.to = s.to.data();
      // (What follows it inherits the whole pending list: the rest was not looked at.)
      if (now != Answer::kFree) return {Step::kCollides, mid, first, count};
    }
    arena.push_back(k);
    largest = std::max(largest, (k < pairs ? s.interval_pair_speed[k] : s.interval_speed[k - pairs]) * half);
  }
  const std::size_t left = arena.size() - failing;
  if (left == 0) return {Step::kCertified};
  // Each failing component came within its proxies' error and its growth of a collision at the
  // midpoint (failure_within_tolerance): where every one fits the tolerance and may take its
  // shortcut on this motion, the motion counts as colliding there. (The room first: whether a
  // component may take the shortcut costs end checks.)
  const auto failed = arena.begin() + static_cast<std::ptrdiff_t>(failing);
  if (tolerance_asked_ && std::all_of(failed, arena.end(), [&](int k) { return failure_within_tolerance(k, posed); }) &&
      std::all_of(failed, arena.end(), [&](int k) { return tolerant_component(k, ends); })) {
    return {Step::kCollides, mid, failing, left};
  }
  // Growth below the level is tested by exact distances: a failure with the motion's own growth
  // within min_clearance puts a pair within padding + 2 min_clearance at the midpoint (counted as
  // colliding, as advancement counts one within min_clearance), unless a component that failed
  // is held to a lower floor by an end closer than that (end_clearance_floor).
  if (2.0 * largest <= options_.min_clearance && (largest <= level_ / 2 || proxies_.empty()) &&
      !closer_end_splits(&*failed, arena.data() + arena.size(), half, ends)) {
    return {Step::kCollides, mid, failing, left};
  }
  // Every component that failed did so on an exact distance at the midpoint: each is free for
  // as long as it cannot have closed that gap, the smallest of which frees a middle stretch.
  Step split{Step::kSplit, -1.0, failing, left};
  split.largest = largest;
  if (std::isfinite(posed.free_radius) && posed.free_radius > 0.0) {
    split.free_lo = std::max(lo, mid - posed.free_radius);
    split.free_hi = std::min(hi, mid + posed.free_radius);
  }
  return split;
}

// Component k failed an interval whose midpoint is `mid`: its proxies at the level it walked
// (walked_level of its growth), grown by its growth, met a counterpart's (a pair) or an object,
// which puts the link within the level's error, the growth and twice the test's rounding margin
// (posing, then the balls' test) of a collision at the midpoint. Does that fit the tolerance? Not
// for a link with an octree: a grown leaf larger than a few voxels counts as meeting it untested
// (link_octree_check), so a failure there puts the link nowhere in particular.
bool SceneChecker::failure_within_tolerance(int k, const Posed& mid) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const int pairs = static_cast<int>(pair_rates_.size());
  if (k >= pairs) {
    if (octree_) return false;
    const int l = k - pairs;
    const ProxyLevel* walked = walked_level(mid.growth[l]);
    const double margin = 2.0 * proxy_pose_margin(walked->links[l], mid.poses[l]);
    return interval_within_tolerance(walked->level, Counterpart::kObject, mid.growth[l] + margin, options_.tolerance);
  }
  const auto [a, b] = m.checked_pairs()[k];
  const double grown = mid.pair_growth[k];
  const ProxyLevel* walked = walked_level(grown);
  const double margin = 2.0 * (proxy_pose_margin(walked->links[a], mid.poses[a]) + proxy_pose_margin(walked->links[b], mid.poses[b]));
  return interval_within_tolerance(walked->level, Counterpart::kLink, grown + margin, options_.tolerance);
}

// Per link and per self pair, how fast they can move (close) per unit fraction of this segment.
void SceneChecker::motion_speeds(const double* start, const double* goal) const {
  MotionScratch& s = motion_scratch();
  const RobotCollisionModel& m = checker_.collision_model();
  s.speed.assign(m.shapes().size(), 0.0);
  for (const int l : links_) s.speed[l] = checker_.link_speed(l, start, goal);
  s.delta.resize(checker_.model().variable_count());
  for (std::size_t j = 0; j < s.delta.size(); ++j) s.delta[j] = goal[j] - start[j];
  chain_deltas(s.delta.data(), s.chain_delta, s.turning_total, s.turning_moving);
  s.interval_speed.assign(s.speed.size(), 0.0);
  s.interval_pair_speed.assign(pair_rates_.size(), 0.0);
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

// With the root at the origin, a link posed from its parent's pose is the same bits whether the
// parent was posed now or at the motion's start (the same products of the same values), so the
// links no moving joint is above keep their start poses. (Otherwise every link is posed again:
// the root pose is applied after the chain.)
void SceneChecker::moving_links(const double* start, const double* goal, const Posed& at_start) const {
  MotionScratch& s = motion_scratch();
  const KinematicsPlan& plan = checker_.collision_model().kinematics();
  s.partial = root_at_origin_;
  if (!s.partial) return;
  s.link_moves.assign(plan.link_count(), 0);
  s.moving_steps.clear();
  const auto& steps = plan.step_list();
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const KinematicsPlan::Step& step = steps[i];
    const bool turns = step.variable >= 0 && start[step.variable] != goal[step.variable];
    s.link_moves[step.link] = s.link_moves[step.parent] || turns;
    if (s.link_moves[step.link]) s.moving_steps.push_back(static_cast<std::uint32_t>(i));
  }
  s.moving.clear();
  s.needed_first = std::numeric_limits<std::size_t>::max();  // (none found for this motion yet)
  s.still_largest = 0.0;
  for (const int l : links_) {
    if (s.link_moves[l]) {
      s.moving.push_back(l);
    } else {
      s.still_largest = std::max(s.still_largest, at_start.centre_norms[l]);
    }
  }
  Posed& mid = s.midpoint;
  mid.poses = at_start.poses;
  mid.centres = at_start.centres;
  mid.centre_norms = at_start.centre_norms;
}

// The steps and links with geometry that `count` pending components read: their links and the
// links those hang from, among the moving ones (into needed_steps and needed_moving).
void SceneChecker::needed_links(const int* components, std::size_t count) const {
  MotionScratch& s = motion_scratch();
  const KinematicsPlan& plan = checker_.collision_model().kinematics();
  const auto& pairs = checker_.collision_model().checked_pairs();
  const int pair_count = static_cast<int>(pairs.size());
  s.link_needed.assign(plan.link_count(), 0);
  for (std::size_t i = 0; i < count; ++i) {
    const int k = components[i];
    if (k < pair_count) {
      s.link_needed[pairs[k].first] = s.link_needed[pairs[k].second] = 1;
    } else {
      s.link_needed[k - pair_count] = 1;
    }
  }
  s.needed_moving.clear();
  for (const int l : s.moving) {
    if (s.link_needed[l]) s.needed_moving.push_back(l);
  }
  // From the leaves up (a parent's step comes before its children's), each needed link's parent.
  const auto& steps = plan.step_list();
  s.needed_steps.clear();
  for (auto it = s.moving_steps.rbegin(); it != s.moving_steps.rend(); ++it) {
    const KinematicsPlan::Step& step = steps[*it];
    if (!s.link_needed[step.link]) continue;
    if (step.parent >= 0) s.link_needed[step.parent] = 1;
    s.needed_steps.push_back(*it);
  }
  std::reverse(s.needed_steps.begin(), s.needed_steps.end());
}

void SceneChecker::pose_moving_links(const double* state, Posed& posed, const int* components, std::size_t count) const {
  MotionScratch& s = motion_scratch();
  if (!s.partial) return pose_links(state, posed);
  const RobotCollisionModel& m = checker_.collision_model();
  // With some components certified, only the links the others read are posed (a two-arm robot's
  // last intervals of a motion ask one arm's forearm against a shelf): the rest keep poses no
  // test reads.
  const bool some = count < components_.size();
  // (The components lie in the pending list, which only grows within a motion: a sibling's list
  // is at the same place.)
  const std::size_t first = static_cast<std::size_t>(components - s.pending.data());
  if (some && (first != s.needed_first || count != s.needed_count)) {
    needed_links(components, count);
    s.needed_first = first, s.needed_count = count;
  }
  const std::vector<std::uint32_t>& steps = some ? s.needed_steps : s.moving_steps;
  posed.state = state;
  m.kinematics().compute_steps(state, posed.poses, steps.data(), steps.size());
  double largest = s.still_largest;
  for (const int l : some ? s.needed_moving : s.moving) {
    Vec3& c = posed.centres[l];
    transform_point(posed.poses[l], m.bounds()[l].center.data(), c.data());
    posed.centre_norms[l] = std::sqrt((c[0] * c[0] + c[1] * c[1]) + c[2] * c[2]);  // as Vec3::norm()
    largest = std::max(largest, posed.centre_norms[l]);
  }
  posed.largest_norm = largest;
}

// The rates of the interval [lo, hi] of the segment into the scratch's interval speeds (every
// component).
void SceneChecker::speeds_over(const double* start, const double* goal, double lo, double hi) const {
  thread_local Posed posed;
  thread_local std::vector<double> mid;
  MotionScratch& s = motion_scratch();
  motion_speeds(start, goal);
  mid.resize(s.delta.size());
  for (std::size_t j = 0; j < mid.size(); ++j) mid[j] = start[j] + 0.5 * (lo + hi) * s.delta[j];
  pose_links(mid.data(), posed);
  std::vector<int> every(pair_rates_.size());
  std::iota(every.begin(), every.end(), 0);
  for (const int l : links_) every.push_back(static_cast<int>(pair_rates_.size()) + l);
  const IntervalRates rates{s.delta.data(),      s.chain_delta.data(),     s.turning_total.data(),
                            s.speed.data(),      s.pair_speed.data(),      s.interval_speed.data(),
                            s.interval_pair_speed.data(), &s.sums,         &s.axes,
                            &s.turning_moving,   &s.chain_reads,           &s.read_links};
  interval_speeds(posed, 0.5 * (hi - lo), every.data(), every.size(), rates);
}

double SceneChecker::link_growth(int link, const double* start, const double* goal, double lo, double hi) const {
  speeds_over(start, goal, lo, hi);
  const double g = motion_scratch().interval_speed[link] * 0.5 * (hi - lo);
  return grown_growth(g);
}

double SceneChecker::pair_growth(std::size_t pair, const double* start, const double* goal, double lo, double hi) const {
  speeds_over(start, goal, lo, hi);
  const double g = motion_scratch().interval_pair_speed[pair] * 0.5 * (hi - lo);
  return grown_growth(g);
}

MotionResult SceneChecker::check_motion(const double* start, const double* goal, bool earliest) const {
  checker_.require_finite_state(start, "motion check");
  checker_.require_finite_state(goal, "motion check");
  MotionResult result;
  if (known_motion(start, goal, earliest, result)) return result;
  if (within_free_motion(start, goal)) {  // states_checked 0: none checked by this call
    result.valid = result.certified = true;
    result.last_valid_fraction = 1.0;
    return result;
  }
  result = check_motion_once(start, goal, earliest);
  remember_motion(start, goal, earliest, result);
  if (result.valid) remember_free_motion(start, goal);
  return result;
}

MotionResult SceneChecker::check_motion_once(const double* start, const double* goal, bool earliest) const {
  const std::size_t n = checker_.model().variable_count();
  MotionResult result;
  MotionScratch& s = motion_scratch();
  // The state at fraction f of the motion, into `out` (which holds the start's values): only the
  // variables that change are written (a two-arm robot's 14 of its 45).
  std::vector<int>& changing = s.changing;
  changing.clear();
  for (std::size_t j = 0; j < n; ++j) {
    if (std::memcmp(start + j, goal + j, sizeof(double)) != 0) changing.push_back(static_cast<int>(j));
  }
  s.state.assign(start, start + n);
  s.from.assign(start, start + n);
  s.to.assign(start, start + n);
  auto at = [&](double f, double* out) {
    for (const int j : changing) out[j] = f >= 1.0 ? goal[j] : start[j] + f * (goal[j] - start[j]);
    return out;
  };
  // The ends first (a planner's goal state is often the colliding one); the start's collision is
  // the earliest there is.
  result.states_checked = 2;
  Posed* ends = s.ends.data();
  for (int e = 0; e < 2; ++e) {
    ends[e].growth = ends[e].pair_growth = nullptr;
    ends[e].tolerant_flag = options_.states_at_tolerance;
    ends[e].ends = nullptr;
  }
  // The start is posed now (the intervals take its still links' poses); the goal when a test
  // reads it: its check, unless it is known free, or the tolerance's end checks.
  pose_links(start, ends[0]);
  s.goal = goal;
  s.goal_posed = false;
  // (An end this thread found free with this checker, as the state it is, is not checked again;
  // nor one on a segment it certified free: the simplifier's shortcuts start and end on the
  // path's segments, between vertices the memory of states no longer holds.)
  auto end_collides = [&](int e) {
    const double* q = e == 0 ? start : goal;
    if (known_free(q)) return false;
    if (within_free_motion(q, q)) {
      remember_free(q);
      return false;
    }
    if (e == 1) pose_goal(ends);
    if (check_posed(ends[e]) != Answer::kFree) return true;
    remember_free(q);
    return false;
  };
  double found = end_collides(0) ? 0.0 : end_collides(1) ? 1.0 : -1.0;  // the earliest collision known
  if (found == 0.0 || (found > 0.0 && !earliest)) {
    result.colliding_fraction = found;
    result.certified = true;
    return result;
  }
  s.tolerant.assign(pair_rates_.size() + checker_.collision_model().shapes().size(), tolerance_asked_ ? -1 : 0);
  s.floors_asked = s.floors_lowered = false;
  motion_speeds(start, goal);
  moving_links(start, goal, ends[0]);
  std::vector<int>& arena = s.pending;
  arena.assign(components_.begin(), components_.end());
  std::vector<Interval>& done = s.done;
  std::vector<Interval>& todo = s.todo;
  done.clear();
  todo.assign(1, Interval{0.0, 1.0, 0, components_.size()});
  std::size_t head = 0;
  while (head < todo.size()) {
    const Interval i = earliest ? todo.back() : todo[head];
    earliest ? todo.pop_back() : void(++head);
    // Beyond a collision already found, or (the earliest one) within a thousandth of the motion
    // before it: the last valid state is then that close to it, which is all a planner needs.
    if (found >= 0.0 && i.lo >= found - (earliest ? kEarliestResolution : 0.0)) continue;
    if (++result.states_checked > options_.max_intervals) {
      result.message = "not certified after " + std::to_string(options_.max_intervals) + " intervals";
      result.last_valid_fraction = certified_prefix(done);
      return result;
    }
    const Step step = check_interval(i.lo, i.hi, i.first, i.count, at, ends);
    if (step.outcome == Step::kCertified) {
      done.push_back(i);
    } else if (step.outcome == Step::kCollides) {
      found = found < 0.0 ? step.at : std::min(found, step.at);
      if (!earliest) break;
      if (step.at > i.lo) todo.push_back({i.lo, step.at, step.first, step.count});
    } else if (i.lo == 0.0 && i.hi == 1.0 && step.free_hi <= step.free_lo && step.largest > kFirstPieceGrowth) {
      // The whole motion failed with a growth far beyond any clearance: its halves would fail too.
      // Pieces whose growth is about kFirstPieceGrowth instead (each with the components the
      // whole could not certify).
      const int m = static_cast<int>(std::min(64.0, std::ceil(step.largest / kFirstPieceGrowth)));
      spread_order(m, earliest, s.order, s.runs);
      for (const int k : s.order) {
        todo.push_back({static_cast<double>(k) / m, k + 1 == m ? 1.0 : static_cast<double>(k + 1) / m, step.first, step.count});
      }
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
