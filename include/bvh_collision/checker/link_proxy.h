// Bounded-error sphere proxies of a link (DESIGN.md section 2, the tolerance): a tree of spheres
// built once per link and per proxy level e, such that
//   (a) the leaf spheres together contain the link's geometry, solids included, and
//   (b) every point of every leaf sphere lies within e/2 of the link (one-sided Hausdorff bound).
// So two links whose proxies are apart are apart, and two links whose proxies overlap are at
// most e apart: a query at tolerance t >= e may answer from the proxies alone and keep the
// contract (collision whenever d <= padding, free whenever d > padding + t, no false negative).
//
// How the bound is proven at build time: the link's box is cut into cubes, octree fashion. For a
// cube with centre c and half-diagonal h, d = the exact distance from c to the link's surface
// (point-to-mesh distance over the BVH, or the primitive's closed form). If c is outside the link
// and d > h, no point of the cube belongs to the link: the cube is dropped. If d + h <= e/2, every
// point of the cube's ball is within e/2 of the surface: a leaf. If c is inside the solid (exact
// winding number, or the primitive's test) and h <= d + e/2, every point of the ball is in the
// solid or within h - d <= e/2 of it (a segment from c leaves the solid only after d): a leaf.
// Otherwise the cube is split. Every cube that holds a point of the link is a leaf or split, so
// the leaves cover the link; every leaf satisfies its inequality, so (b) holds. The inequalities
// are tested with the margins of geometry/safety_margin.h and with e slightly below the level,
// so that rounding in the build and in the queries cannot break them.
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
