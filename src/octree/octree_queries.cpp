// The octree queries of the textbook the design started from: point location, box and sphere overlap, ray casting; and clearing a
// box. Every search skips a subtree whose node value is below the occupancy threshold: an inner
// node holds the maximum of its children, so nothing below it is occupied.
#include <algorithm>
#include <array>
#include <limits>

#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/octree/cube_walk.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {
namespace {

struct KeyRange {
  OctreeKey lo, hi;
};

// The keys of min and max (OctoMap's rule), clamped to the key range: a box reaching past it is
// cut, not lost.
KeyRange key_range(const OctreeGrid& grid, const Vec3& min, const Vec3& max) {
  KeyRange r;
  for (int i = 0; i < 3; ++i) {
    r.lo.k[i] = grid.key(min[i]).value_or(min[i] < 0 ? 0 : 0xFFFF);
    r.hi.k[i] = grid.key(max[i]).value_or(max[i] < 0 ? 0 : 0xFFFF);
  }
  return r;
}

// Does the node (lowest voxel `corner`, at `depth`) hold a key of the range?
bool meets(const KeyRange& r, const OctreeKey& corner, int depth) {
  const int span = (1 << (kOctreeDepth - depth)) - 1;
  for (int i = 0; i < 3; ++i) {
    if (int(corner.k[i]) + span < int(r.lo.k[i]) || corner.k[i] > r.hi.k[i]) return false;
  }
  return true;
}

bool inside(const KeyRange& r, const OctreeKey& corner, int depth) {
  const int span = (1 << (kOctreeDepth - depth)) - 1;
  for (int i = 0; i < 3; ++i) {
    if (corner.k[i] < r.lo.k[i] || int(corner.k[i]) + span > int(r.hi.k[i])) return false;
  }
  return true;
}

bool boxes_meet(const Vec3& a_min, const Vec3& a_max, const Vec3& b_min, const Vec3& b_max) {
  return (a_min.array() <= b_max.array()).all() && (b_min.array() <= a_max.array()).all();
}

// Entry and exit of the ray p + s u (u unit, 1/u precomputed) through the closed box, within
// [0, max_range]; false when it misses.
bool slab(const Vec3& p, const Vec3& u, const Vec3& inv, const Vec3& lo, const Vec3& hi, double max_range,
          double& t0, double& t1) {
  t0 = 0.0;
  t1 = max_range;
  for (int i = 0; i < 3; ++i) {
    if (u[i] == 0.0) {
      if (p[i] < lo[i] || p[i] > hi[i]) return false;
      continue;
    }
    double a = (lo[i] - p[i]) * inv[i], b = (hi[i] - p[i]) * inv[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  return true;
}

}  // namespace

std::optional<Octree::Leaf> Octree::locate(const Vec3& p) const {
  const auto key = grid_.key(p);
  if (!key) return std::nullopt;
  const auto found = find(*key);
  if (!found) return std::nullopt;
  OctreeKey corner = *key;
  const auto low_bits = static_cast<std::uint16_t>((1u << (kOctreeDepth - found->depth)) - 1);
  for (auto& k : corner.k) k = static_cast<std::uint16_t>(k & ~low_bits);
  return Leaf{corner, found->depth, found->index, found->log_odds};
}

std::vector<Octree::Leaf> Octree::occupied_in_box(const Vec3& min, const Vec3& max) const {
  std::vector<Leaf> out;
  const auto root = occupied_root(*this);
  if (!root || !(min.array() <= max.array()).all()) return out;
  // One voxel of slack below: a cube whose top face touches `min` belongs to the voxel under it.
  KeyRange range = key_range(grid_, min, max);
  for (auto& k : range.lo.k) k = static_cast<std::uint16_t>(k > 0 ? k - 1 : 0);
  descend_while(
      *this, *root, [&](const OctreeCube& c) { return meets(range, c.corner, c.depth) ? Visit::kEnter : Visit::kSkip; },
      [&](const OctreeCube& c) {
        const Vec3 lo = cube_min(c.corner), hi = lo + Vec3::Constant(cube_size(c.depth));
        if (boxes_meet(lo, hi, min, max)) out.push_back(leaf_of(*this, c));
        return false;
      });
  return out;
}

std::vector<Octree::Leaf> Octree::occupied_in_sphere(const Vec3& centre, double radius, bool any) const {
  std::vector<Leaf> out;
  const auto root = occupied_root(*this);
  if (!root || !(radius >= 0.0) || !centre.allFinite()) return out;
  auto visit = [&](const OctreeCube& c) {
    const Vec3 lo = cube_min(c.corner), hi = lo + Vec3::Constant(cube_size(c.depth));
    return sphere_intersects_box(centre, radius, lo, hi) ? Visit::kEnter : Visit::kSkip;
  };
  descend_while(*this, *root, visit, [&](const OctreeCube& c) {
    out.push_back(leaf_of(*this, c));
    return any;
  });
  return out;
}

// Front to back: children in the order the ray enters them, so the first occupied leaf reached
// is the first hit (the cubes are disjoint, so a later child's entry is past any earlier hit).
std::optional<Octree::RayHit> Octree::cast_ray(const Vec3& origin, const Vec3& direction, double max_range) const {
  const double length = direction.norm();
  if (empty() || !origin.allFinite() || !(length > 0.0) || !std::isfinite(length) || !(max_range >= 0.0)) {
    return std::nullopt;
  }
  const Vec3 u = direction / length, inv = u.cwiseInverse();
  const auto root = occupied_root(*this);
  if (!root) return std::nullopt;
  // A cube's bound is where the ray enters it (infinite when it misses): nearest first, the
  // first leaf reached is the first hit.
  auto entry = [&](const OctreeCube& c) {
    const Vec3 lo = cube_min(c.corner), hi = lo + Vec3::Constant(cube_size(c.depth));
    double t0, t1;
    return slab(origin, u, inv, lo, hi, max_range, t0, t1) ? t0 : std::numeric_limits<double>::infinity();
  };
  std::optional<RayHit> hit;
  nearest_cubes_first(
      *this, *root, entry,
      [&](const OctreeCube& c) {
        const double t = entry(c);
        hit = RayHit{leaf_of(*this, c), t, origin + t * u};
        return true;
      },
      [] { return std::numeric_limits<double>::infinity(); });
  return hit;
}

// Every block below `node` goes back to the free list, unwritten (a released slot is written
// when it is reused, so a page shared with a snapshot is not copied to release it). The node
// itself is left to the caller, which unlinks it.
void Octree::release_below(std::int32_t node) {
  const Node n = at(node);
  if (n.children < 0) return;
  for (int b = 0; b < 8; ++b) {
    if (!((n.mask >> b) & 1)) continue;
    release_below(n.children + b);
    --node_count_;
  }
  release_block(n.children);
}

// True when `node` is to be deleted: wholly inside the range, or left without children (as
// OctoMap's deleteNode removes an inner node that lost its last child).
bool Octree::clear_below(std::int32_t node, const OctreeKey& corner, int depth, const OctreeKey& lo, const OctreeKey& hi) {
  const KeyRange range{lo, hi};
  if (inside(range, corner, depth)) {
    release_below(node);
    return true;
  }
  if (is_leaf(node)) expand(node);  // a pruned node partly in the box
  for (int b = 0; b < 8; ++b) {
    const std::int32_t c = child(node, b);
    if (c < 0 || !meets(range, child_corner(corner, depth, b), depth + 1)) continue;
    if (clear_below(c, child_corner(corner, depth, b), depth + 1, lo, hi)) {
      Node& n = edit(node);
      n.mask = static_cast<std::uint8_t>(n.mask & ~(1u << b));
      --node_count_;
    }
  }
  if (at(node).mask == 0) {
    release_block(at(node).children);
    return true;  // the caller unlinks it (or the tree is cleared)
  }
  if (!prune(node)) refresh(node);
  return false;
}

void Octree::clear_box(const Vec3& min, const Vec3& max) {
  if (empty() || !min.allFinite() || !max.allFinite() || !(min.array() <= max.array()).all()) return;
  const KeyRange range = key_range(grid_, min, max);
  if (!meets(range, OctreeKey{}, 0)) return;
  revision_ = next_revision();
  if (clear_below(0, OctreeKey{}, 0, range.lo, range.hi)) clear();
}

}  // namespace bvh_collision
