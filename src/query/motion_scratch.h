// SceneChecker's working memory for motions, one per thread (SceneChecker::motion_scratch), and
// the intervals it keeps: shared by the files of its motions (scene_motion.cpp, scene_ends.cpp).
// Private to src/query.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "bvh_collision/query/scene_checker.h"

namespace bvh_collision {
namespace scene_motion {

// An interval of the motion and the components still pending over it (arena[first, first +
// count)): those its parent could not certify; the others are free over the parent, so over it.
struct Interval {
  double lo, hi;
  std::size_t first, count;
};

}  // namespace scene_motion

// A thread's working memory, kept between motions: a planner's millionth motion allocates nothing.
struct SceneChecker::MotionScratch {
  // speed, pair_speed: the motion's chain-length rates; interval_speed, interval_pair_speed: the
  // current interval's (at most those); delta: goal - start.
  std::vector<double> growth, state, speed, pair_speed, pair_growth, from, to, delta, interval_speed, interval_pair_speed, sums;
  std::vector<int> chain_reads, read_links;  // interval_speeds' working memory
  std::vector<double> chain_delta, turning_total;  // chain_deltas' (once a motion)
  std::vector<int> turning_moving;
  std::vector<TurningAxis> axes;
  std::vector<scene_motion::Interval> done;   // certified intervals (check_motion)
  // Intervals still to check: todo[head, end), taken from the front (breadth first) or the back
  // (depth first).
  std::vector<scene_motion::Interval> todo;
  std::vector<int> order;  // pieces of a motion cut at once (spread_order)
  std::vector<std::pair<int, int>> runs;
  std::vector<int> changing;  // the variables a motion changes (check_motion_once)
  std::vector<int> pending;  // a motion's components still to certify, per interval (check_interval)
  std::vector<int> near;     // an interval's pending components its chain-length rates do not certify
  std::vector<int> live;     // an interval's pending components past its bounding-ball sieve
  // Per component: may the tolerance's shortcut take it on this motion? (-1: not asked yet)
  std::vector<signed char> tolerant;
  Posed midpoint;                                   // check_interval's
  std::array<Posed, 2> ends;                        // check_motion's end states
  const double* goal = nullptr;                     // the motion's goal, posed into ends[1] once read
  bool goal_posed = false;
  std::vector<double> end_growth, end_pair_growth;  // tolerant_component's, end_clearance_floor's
  // Per component: the clearance its intervals keep (end_clearance_floor: min_clearance unless
  // one of the motion's ends is itself closer), and whether that was asked this motion; none
  // asked (floors_asked) or none lowered (floors_lowered): min_clearance for every component.
  std::vector<double> floor;
  std::vector<signed char> floor_known;
  bool floors_asked = false, floors_lowered = false;
  // moving_links': the kinematic steps and the links with geometry a motion moves (all when the
  // root pose is not the identity), and the largest centre norm of the others.
  std::vector<std::uint32_t> moving_steps;
  std::vector<int> moving;
  std::vector<char> link_moves;
  // pose_moving_links' for an interval whose pending components read only some links.
  std::vector<char> link_needed;
  std::vector<std::uint32_t> needed_steps;
  std::vector<int> needed_moving;
  // The pending list (pending[first, first + count)) they were found for: the halves of an
  // interval, and the pieces of a motion, share their parent's list (none before a motion's first).
  std::size_t needed_first = 0, needed_count = 0;
  bool partial = false;
  double still_largest = 0.0;
};

}  // namespace bvh_collision
