// Bounded-error sphere proxies of a link (DESIGN.md section 2, the tolerance): a tree of spheres
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
#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

struct LinkShape;

// A sphere of the tree, in depth-first order: its subtree is [index, skip); a leaf has skip ==
// index + 1. Every sphere contains the spheres of its subtree.
struct ProxySphere {
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  std::int32_t skip = 0;
};

class LinkProxy {
 public:
  LinkProxy() = default;
  // The proxy of a link's shapes (in the link frame) at level e > 0. `meshes` holds the BVHs the
  // shapes' mesh indices name; a closed mesh stands for its solid, an open one for its surface.
  static LinkProxy build(const std::vector<LinkShape>& shapes, const std::vector<Bvh<Obb>>& meshes, double level);

  const std::vector<ProxySphere>& spheres() const { return spheres_; }
  bool empty() const { return spheres_.empty(); }
  double level() const { return level_; }
  // The largest distance, proven at build time, of a point of a leaf sphere from the link (<= level / 2).
  double hausdorff_bound() const { return hausdorff_; }
  std::size_t leaf_count() const { return leaves_; }
  std::size_t memory_bytes() const { return spheres_.capacity() * sizeof(ProxySphere); }

 private:
  std::vector<ProxySphere> spheres_;
  double level_ = 0.0;
  double hausdorff_ = 0.0;
  std::size_t leaves_ = 0;
};

// Do the proxies (posed in the world) come within `padding` of each other? A conservative test:
// true whenever two leaf spheres are within padding (rounding can only make it answer true).
bool proxies_overlap(const LinkProxy& a, const Transform& pose_a, const LinkProxy& b, const Transform& pose_b,
                     double padding);

}  // namespace bvh_collision
