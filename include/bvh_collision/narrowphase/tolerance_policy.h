// The tolerance policy, in one place: which method may answer a component of a query (a link
// against another link, an object or the octree) at tolerance eps, by docs/design.md: report
// collision whenever d <= padding, free whenever d > padding + eps, and "a tolerance may be
// served by a coarser model of a link (a proxy) only when that model's error is proven at build
// time to be within the tolerance".
//
// The methods and their error:
// - exact (shape_pairs.h, shape_octree.h): none; a distance query at eps may stop within eps
//   above the true distance, a BVH x octree walk may settle a cube within eps (its slack). The
//   tolerance never widens a reach (a broad phase, a hull test, an octree region): a pair farther
//   apart than its padding may be answered free at every eps, so at eps > 0 the exact path takes
//   the pairs eps = 0 takes and may only stop sooner. A tolerance never costs more than the exact
//   answer (test_tolerance_policy counts the work).
// - clearance grids (model/pair_clearance.h) and the octree's distance field
//   (octree/distance_field.h): proven lower bounds, so they only ever prove "free": used at every
//   tolerance, eps = 0 included.
// - a proxy level e (link_proxy.h): its leaf spheres hold the link and lie within e/2 of it. So
//   proxies apart prove free at every tolerance (they prune, eps = 0 included), and proxies that
//   meet put the link within padding + error of the counterpart, the error being e against
//   another link's proxies (e/2 on each side) and e/2 against an exact obstacle. A level may
//   answer "collision" alone where that error fits eps: e <= eps against a link, e <= 2 eps
//   against an obstacle. Only for boolean questions (no distance, no contacts to report) on
//   solids (the proxies cover a closed mesh's solid; without solids a link inside another is
//   free, which they cannot tell), and against the octree only with its distance field (the
//   proxies' leaf test reads the field's occupancy grid).
// - a certified motion (query/scene_checker.h, motion_check.cpp) grows each interval's proxies
//   by how far the links move in it; an interval that still fails counts as colliding once growth
//   and proxy error fit eps. It walks the levels down to the coarsest that decides (e <= eps, the
//   same as a state). It used to stop at eps / 2, leaving the other half as room for the growth
//   near a contact; walking one more, finer level cost more than that room saved: stopping at eps
//   took ur5e's 10 mm plans 15-20 % less time (three seeds of bench_planning), the demo's certified
//   sweep at 10 mm 318 us instead of 657 (at 20 mm 72 instead of 298), panda's plans the same.
#pragma once

namespace bvh_collision {

// The other side of a link in a component.
enum class Counterpart { kLink, kObject, kOctree };

// How far an answer from proxy level `level` can be off against `other`: the level against a
// link's proxies, half of it against an exact obstacle.
double proxy_error(double level, Counterpart other);

struct ToleranceQuestion {
  double tolerance = 0.0;  // eps, finite and >= 0
  Counterpart other = Counterpart::kLink;
  bool boolean = true;        // only collision or not: no distance, no contacts asked for
  bool solids = true;         // closed meshes are solids (the default)
  bool motion = false;        // the intervals of a certified motion, not one state
  bool octree_field = false;  // against the octree: its distance field is there
};

// How proxy levels may serve the question (RobotAccelerators::proxies_for takes these bounds;
// 0: no level).
struct ProxyUse {
  // A level e <= this may answer alone (its overlap counts as collision); a certified motion walks
  // the levels down to the coarsest up to this too.
  double decide_up_to = 0.0;
};
ProxyUse proxy_use(const ToleranceQuestion& question);

// A certified motion's interval that a component still fails at proxy level `level` against
// `other`, its proxies grown by `growth` (how far its link moves, or its pair closes, over half the
// interval, with any rounding margin of the test): at the interval's midpoint the link's proxies
// came within the growth of the counterpart (its proxies grown once, not on both sides), so the
// link came within the level's error and the growth of a collision there, on the motion. May the
// tolerance take the motion as colliding there? When that fits the tolerance: against an obstacle
// a growth up to half the tolerance at a level of the tolerance itself (the level a motion walks
// down to), against a link none.
bool interval_within_tolerance(double level, Counterpart other, double growth, double tolerance);

}  // namespace bvh_collision
