// Bounded-error sphere proxies of a link (docs/design.md, the tolerance): a tree of spheres
// built once per link and per proxy level e, such that
//   (a) the leaf spheres together contain the link's geometry, solids included, and
//   (b) every point of every leaf sphere lies within e/2 of the link (one-sided Hausdorff bound).
// So two links whose proxies are apart are apart, and two links whose proxies overlap are at
// most e apart: a query at tolerance t >= e may answer from the proxies alone and keep the
// contract (collision whenever d <= padding, free whenever d > padding + t, no false negative).
//
// How it is built and proven. Every sphere chosen satisfies (b) by construction: an interior
// sphere is centred at a point c inside the solid (exact winding number, or the primitive's own
// test) with radius depth(c) + e/2, depth(c) being the exact distance from c to the surface, so a
// segment from c leaves the solid only after depth(c) and no point of the sphere is farther than
// e/2 from it; a surface sphere is centred on the link with radius e/2. A greedy set cover of
// sample points picks spheres (the largest interior sphere through each sampled surface point,
// interior spheres on a grid); it only guides. The proof of (a) follows for a boundary made of
// triangles (meshes, boxes): every triangle, split in four as often as needed, lies with a
// margin delta inside one chosen sphere (all three corners inside it: convexity), and a piece
// no sphere holds gets one of its own; then cubes from the box down: a cube inside one sphere,
// with no point of the solid, or within delta of the surface (covered by the margin) is done,
// one deep inside gets the interior sphere at its centre, the rest are split. Cylinders and
// capsules are covered by cubes alone (a cube with centre c and half-diagonal h: dropped when c
// is outside and farther than h from the link, a sphere of its own when d(c) + h <= e/2 or, c
// inside, h <= depth(c) + e/2). A sphere primitive is its own proxy. The inequalities carry the
// margins of geometry/safety_margin.h and e slightly below the level, so that rounding in the
// build and in the queries cannot break them.
#pragma once

#include <cstdint>
#include <vector>

#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/tree_walk.h"
#include "bvh_collision/geometry/types.h"
#include "bvh_collision/narrowphase/shape.h"

namespace bvh_collision {

// A sphere of the tree, in depth-first order: its subtree is [index, skip); a leaf has skip ==
// index + 1. Every sphere contains the spheres of its subtree.
struct ProxySphere {
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  std::int32_t skip = 0;
};

// The work a build did, counted (docs/performance.md, "proxy build"): what a test bounds instead
// of a time. Every cube and surface piece asks a constant number of nearby spheres (a hashed grid
// of the chosen ones) and at most one distance and one containment query of the mesh's BVH.
struct ProxyBuildStats {
  std::size_t cubes = 0;             // cubes of the volume proofs
  std::size_t surface_pieces = 0;    // triangle pieces of the surface proofs
  std::size_t sphere_tests = 0;      // chosen spheres tested for holding a cube or a piece
  std::size_t distance_queries = 0;  // distances (or "closer than") to the surface asked
  std::size_t inside_queries = 0;    // point-in-solid tests asked
  std::size_t bvh_volume_tests = 0;  // BVH volumes those queries opened
  std::size_t triangle_tests = 0;    // triangles measured from a cube's kept list (not through the BVH)
  std::size_t candidates = 0;        // spheres the greedy start chose among
  std::size_t leaves = 0;            // leaf spheres built
};

class LinkProxy {
 public:
  LinkProxy() = default;
  // The proxy of a link's shapes (in the link frame) at level e > 0; a closed mesh stands for its
  // solid, an open one for its surface. The work is added to `stats` when given.
  static LinkProxy build(const std::vector<BodyShape>& shapes, double level, ProxyBuildStats* stats = nullptr);

  const std::vector<ProxySphere>& spheres() const { return spheres_; }
  bool empty() const { return spheres_.empty(); }
  double level() const { return level_; }
  // The largest distance, proven at build time, of a point of a leaf sphere from the link (<= level / 2).
  double hausdorff_bound() const { return hausdorff_; }
  std::size_t leaf_count() const { return leaves_; }
  std::size_t memory_bytes() const { return spheres_.capacity() * sizeof(ProxySphere); }

 private:
  friend struct LinkProxyFile;  // narrowphase/link_proxy_cache.cpp: stores and restores it as built

  std::vector<ProxySphere> spheres_;
  double level_ = 0.0;
  double hausdorff_ = 0.0;
  std::size_t leaves_ = 0;
};

// A leaf sphere of each of two proxies that last met (indices into their spheres(); -1: none).
// A planner's next state, or a motion's next interval, mostly meets where the last one did, and
// that one test spares the walk down to it.
struct ProxyWitness {
  std::int32_t a = -1;
  std::int32_t b = -1;
};

// Do the proxies (posed in the world) come within `padding` of each other? A conservative test:
// true whenever two leaf spheres are within padding (rounding can only make it answer true).
// With a witness, its leaf pair is tested first (any indices: ones that are not a leaf pair of
// these proxies are passed over), and a leaf pair found to meet is written to it.
bool proxies_overlap(const LinkProxy& a, const Transform& pose_a, const LinkProxy& b, const Transform& pose_b,
                     double padding, ProxyWitness* witness = nullptr);

// A lower bound on the distance between the two links: the smallest gap between a leaf sphere of
// each, less a rounding margin, clamped at 0; `best` (or more) when no pair of leaves is closer
// than `best`. The leaves contain the links, so it is at most their distance, and every leaf point
// lies within level / 2 of its link, so it is at least their distance less a's and b's
// hausdorff_bound(): certified motion steps by it (a clearance lower bound within e).
// A slack lets far pairs cost a few tests: a pair of spheres whose gap exceeds `exact_below` and
// is within a factor 1 + relative_slack of the smallest found is not opened, its gap counts
// instead. The answer stays a lower bound, is at least the exact one divided by 1 + slack, and
// equals it when at most exact_below (an unopened gap exceeds that).
struct ProxySlack {
  double relative = 0.0;
  double exact_below = 0.0;
  bool leaves(double gap, double best) const { return gap > exact_below && gap * (1.0 + relative) >= best; }
};
double proxies_distance(const LinkProxy& a, const Transform& pose_a, const LinkProxy& b, const Transform& pose_b,
                        double best, const ProxySlack& slack = {});

// How far a sphere centre of the posed proxy can land from its exact place through rounding.
inline double proxy_pose_margin(const LinkProxy& proxy, const Transform& pose) {
  const ProxySphere& root = proxy.spheres().front();
  return pose_margin(pose.t.norm() + root.center.norm() + root.radius);
}

// The link (its proxy posed at `pose`) against one obstacle, through a test of a ball against it.
// Every sphere contains its subtree, so a ball that misses the obstacle prunes its subtree; the
// spheres are stored depth first with `skip` past each subtree, so the walk needs no stack
// (geometry/tree_walk.h's skip_walk).
//
// proxy_meets_obstacle: does some leaf sphere, grown by `padding`, meet the obstacle?
// `meets(centre, radius, leaf)` must answer true whenever the ball meets it; for a ball that is
// not a leaf it may answer true more often (a cheap test that only prunes). True means the link lies within padding + level / 2
// of the obstacle; false that it is farther than padding.
// With `witness` (a leaf's index, as ProxyWitness keeps them for a pair; any other value is passed
// over), that leaf is asked first, and the leaf that meets is written to it.
template <class BallMeets>
bool proxy_meets_obstacle(const LinkProxy& proxy, const Transform& pose, double padding, BallMeets&& meets,
                          std::int32_t* witness = nullptr) {
  if (proxy.empty()) return false;
  const std::vector<ProxySphere>& s = proxy.spheres();
  const double grow = padding + proxy_pose_margin(proxy, pose);
  if (witness != nullptr && *witness >= 0 && *witness < static_cast<std::int32_t>(s.size()) && s[*witness].skip == *witness + 1 &&
      meets(Vec3(pose * s[*witness].center), s[*witness].radius + grow, true)) {
    return true;
  }
  bool hit = false;
  skip_walk(static_cast<std::int32_t>(s.size()), [&](std::int32_t i) { return s[i].skip; }, [&](std::int32_t i, bool leaf) {
    if (!meets(Vec3(pose * s[i].center), s[i].radius + grow, leaf)) return Visit::kSkip;
    hit = leaf;
    if (leaf && witness != nullptr) *witness = i;
    return leaf ? Visit::kStop : Visit::kEnter;
  });
  return hit;
}

// proxy_obstacle_distance: min(best, the smallest `distance(centre, radius, best)` over the leaf
// spheres), where `distance` is a lower bound on the distance from the ball to the obstacle (0 if
// they meet) and returns best or more when the ball is not closer than best. With an exact ball
// distance the result lies within hausdorff_bound() below the link's distance. A slack leaves
// spheres unopened as in proxies_distance.
template <class BallDistance>
double proxy_obstacle_distance(const LinkProxy& proxy, const Transform& pose, double best, BallDistance&& distance,
                               const ProxySlack& slack = {}) {
  if (proxy.empty()) return best;
  const std::vector<ProxySphere>& s = proxy.spheres();
  const double grow = proxy_pose_margin(proxy, pose);
  double unopened = best;
  skip_walk(static_cast<std::int32_t>(s.size()), [&](std::int32_t i) { return s[i].skip; }, [&](std::int32_t i, bool leaf) {
    const double d = distance(Vec3(pose * s[i].center), s[i].radius + grow, best);
    if (d >= best) return Visit::kSkip;
    if (leaf) {
      best = d;
      return Visit::kSkip;
    }
    if (slack.leaves(d, best)) {
      unopened = std::min(unopened, d);
      return Visit::kSkip;
    }
    return Visit::kEnter;
  });
  return std::min(best, unopened);
}

}  // namespace bvh_collision
