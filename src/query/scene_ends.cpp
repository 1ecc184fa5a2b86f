// SceneChecker's questions about a motion's two ends (query/scene_checker.h): may the tolerance's
// shortcut take a component on this motion, and what clearance must its intervals keep when an
// end is itself closer to a collision than min_clearance.
#include <algorithm>
#include <vector>

#include "bvh_collision/query/scene_checker.h"
#include "motion_scratch.h"

namespace bvh_collision {

// The motion's goal into ends[1], the first time a test reads it.
void SceneChecker::pose_goal(Posed* ends) const {
  MotionScratch& s = motion_scratch();
  if (s.goal_posed) return;
  pose_links(s.goal, ends[1]);
  s.goal_posed = true;
}

// At a tolerance, a motion may count as colliding where a component (a self pair, a link against
// the environment) comes within the tolerance, unless that component already is at one of its
// ends: a planner must be able to leave a state it accepted. (A failing interval is taken as
// colliding only where its level's error leaves room for its growth within the tolerance:
// failure_within_tolerance; the midpoints are answered at the tolerance with any level.) May the
// shortcut take component k on this motion? Asked only of components that fail somewhere, and
// answered once per motion: the proxies grown by the tolerance at both ends (`ends`, posed) must
// prove it clear of the tolerance there.
bool SceneChecker::tolerant_component(int k, Posed* ends) const {
  signed char& known = motion_scratch().tolerant[k];
  if (known < 0) known = clear_at_ends(k, ends, options_.tolerance, false) ? 1 : 0;
  return known != 0;
}

bool SceneChecker::clear_at_ends(int k, Posed* ends, double grow, bool exact) const {
  MotionScratch& s = motion_scratch();
  s.end_growth.assign(checker_.collision_model().shapes().size(), grow);
  s.end_pair_growth.assign(pair_rates_.size(), grow);
  pose_goal(ends);
  for (int e = 0; e < 2; ++e) {
    Posed& end = ends[e];  // check_motion's own posed ends
    end.growth = s.end_growth.data();
    end.pair_growth = s.end_pair_growth.data();
    end.from = end.to = nullptr;
    end.tolerant_flag = !exact;  // not exact: no exact distances, the proxies decide or it is not clear
    end.ends = nullptr;
    end.half = 0.0;
    if (component_check(k, end) != Answer::kFree) return false;
  }
  return true;
}

// A certified interval keeps each component farther than a floor from every collision, and one
// whose failing components all moved less than half their floor over it counts as colliding
// (check_interval): that ends the bisection. The floor is min_clearance, unless one of the
// motion's ends is itself closer for that component. Such an end is a valid state (touching is
// collision, 0.2 um is not) that a planner must be able to reach and leave, and no interval next
// to it keeps min_clearance. Then the floor is the largest min_clearance / 2^j whose double both
// ends are proven clear of, by exact distances: about a quarter to a half of the nearer end's
// clearance, so the intervals next to it can be certified once their growth is below that, and
// the bisection still ends. Not below kLeastClearance: closer than twice that, the poses'
// rounding margins (1e-9 of a metre's coordinates, safety_margin.h) are a fifth of the clearance
// and more, and the motion is answered colliding there as before. Once a motion per component, and only
// for a component about to end a bisection.
double SceneChecker::end_clearance_floor(int k, Posed* ends) const {
  constexpr double kLeastClearance = 1e-8;
  MotionScratch& s = motion_scratch();
  if (!s.floors_asked) {
    s.floor.assign(s.tolerant.size(), options_.min_clearance);
    s.floor_known.assign(s.tolerant.size(), 0);
    s.floors_asked = true;
  }
  if (s.floor_known[k] != 0) return s.floor[k];
  s.floor_known[k] = 1;
  for (double c = options_.min_clearance; c >= kLeastClearance; c *= 0.5) {
    if (!clear_at_ends(k, ends, 2.0 * c, true)) continue;
    if (c < options_.min_clearance) {
      s.floor[k] = c;
      s.floors_lowered = true;
    }
    break;
  }
  return s.floor[k];
}

// The failing components of an interval [first, last) all moved less than half min_clearance
// over its half-width `half`: is one of them held to a lower floor for a close end, and moving
// more than half of that? Then the interval is split, not counted as colliding.
bool SceneChecker::closer_end_splits(const int* first, const int* last, double half, Posed* ends) const {
  MotionScratch& s = motion_scratch();
  const int pairs = static_cast<int>(pair_rates_.size());
  return std::any_of(first, last, [&](int k) {
    const double g = (k < pairs ? s.interval_pair_speed[k] : s.interval_speed[k - pairs]) * half;
    return 2.0 * g > end_clearance_floor(k, ends);
  });
}

}  // namespace bvh_collision
