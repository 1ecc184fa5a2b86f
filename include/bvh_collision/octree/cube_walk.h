// The walks of the octree, written once: every query that descends the tree alone (a box, a
// ball, a primitive, a point's nearest cube, a solid's inside) is one of the first two loops with
// its own callbacks, in the spirit of OctoMap's leaf iterators with a "descend while the
// predicate holds" test; the tree's own listings (its leaves, the .ot node stream) are the third.
//
//   descend_while(tree, start, visit, leaf, children)   visit(cube) -> Visit, leaf(cube) -> stop?
//   nearest_cubes_first(tree, start, bound, leaf, cutoff)
//   walk_nodes(tree, visit, order)                       every node, free ones too
//
// The first two reach only occupied cubes (an inner cube is occupied when some cube inside it is).
// Header-only: the callbacks are lambdas, inlined into each query's loop.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "bvh_collision/geometry/traversal_stack.h"
#include "bvh_collision/geometry/tree_walk.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

// A node of the octree with its cube: depth, the key of its lowest voxel, its index (docs/design.md's numbering).
struct OctreeCube {
  std::int32_t node;
  int depth;
  OctreeKey corner;
  std::uint64_t index;
};

// Every child (a mask of the child bits b of docs/design.md: x is bit 2, y bit 1, z bit 0).
struct AllChildren {
  std::uint8_t operator()(const OctreeCube&) const { return 0xFF; }
};

// The root as a cube, when the tree has an occupied one.
inline std::optional<OctreeCube> occupied_root(const Octree& tree) {
  if (tree.root() < 0 || !tree.occupied(tree.value(tree.root()))) return std::nullopt;
  return OctreeCube{tree.root(), 0, OctreeKey{}, 0};
}

// The leaf record of a cube (as Octree::leaves() lists it).
inline Octree::Leaf leaf_of(const Octree& tree, const OctreeCube& c) {
  return {c.corner, c.depth, c.index, tree.value(c.node)};
}

// Calls f(child cube) for each occupied child of `c` whose bit is set in `which`.
template <class F>
void for_occupied_children(const Octree& tree, const OctreeCube& c, F&& f, std::uint8_t which = 0xFF) {
  unsigned bits = which & tree.child_mask(c.node);
  const std::int32_t first = tree.children_block(c.node);
  while (bits) {
    const int b = __builtin_ctz(bits);
    bits &= bits - 1;
    const std::int32_t child = first + b;
    if (tree.occupied(tree.value(child))) {
      f(OctreeCube{child, c.depth + 1, child_corner(c.corner, c.depth, b), child_index(c.index, b)});
    }
  }
}

// The octree's occupied cubes as geometry/tree_walk.h walks them: children in docs/design.md's order
// (child 0 walked first), only occupied ones, and of those only the ones `which(cube)` masks in.
template <class MaskFn = AllChildren>
struct OccupiedCubeView {
  using Node = OctreeCube;
  static constexpr std::size_t kMaxChildren = 8;
  const Octree& tree;
  MaskFn which;
  bool is_leaf(const OctreeCube& c) const { return tree.is_leaf(c.node); }
  template <class F>
  void children(const OctreeCube& c, F&& f) const {
    unsigned bits = which(c) & tree.child_mask(c.node);
    const std::int32_t first = tree.children_block(c.node);
    while (bits) {  // highest child bit pushed first, so child 0 is walked first
      const int b = 31 - __builtin_clz(bits);
      bits &= ~(1u << b);
      const std::int32_t child = first + b;
      if (tree.occupied(tree.value(child))) f(OctreeCube{child, c.depth + 1, child_corner(c.corner, c.depth, b), child_index(c.index, b)});
    }
  }
};

// Depth first from `start` (an occupied cube): `visit(cube)` decides for every cube reached; an
// entered leaf goes to `leaf(cube)`, which returns true to stop; `children(cube)` masks which
// children of an entered inner cube are reached (a cheap integer range test, say).
template <class VisitFn, class LeafFn, class MaskFn = AllChildren>
void descend_while(const Octree& tree, const OctreeCube& start, VisitFn&& visit, LeafFn&& leaf,
                   MaskFn&& children = {}) {
  depth_first_walk(OccupiedCubeView<MaskFn&>{tree, children}, start, visit, leaf);
}

// Depth first from `start`, nearest child first, pruned by bounds: a cube whose `bound(cube)` is
// not below `cutoff()` is never entered. `leaf(cube)` lowers the cutoff as it finds answers and
// returns true to stop.
template <class BoundFn, class LeafFn, class CutoffFn>
void nearest_cubes_first(const Octree& tree, const OctreeCube& start, BoundFn&& bound, LeafFn&& leaf,
                         CutoffFn&& cutoff) {
  nearest_first_walk(OccupiedCubeView<>{tree, {}}, start, bound, leaf, cutoff);
}

// Orders of a cube's children by child bits b (docs/design.md): that numbering's (b = 0 first) and OctoMap's (its x
// is bit 0 where docs/design.md's is bit 2: the order of the .ot node stream).
inline constexpr std::array<std::uint8_t, 8> kSeedChildOrder{0, 1, 2, 3, 4, 5, 6, 7};
inline constexpr std::array<std::uint8_t, 8> kOctomapChildOrder{0, 4, 2, 6, 1, 5, 3, 7};

// Every node of the octree, free and occupied, as geometry/tree_walk.h walks them: the children
// of a node in `order`.
struct OctreeNodeView {
  using Node = OctreeCube;
  static constexpr std::size_t kMaxChildren = 8;
  const Octree& tree;
  const std::array<std::uint8_t, 8>& order;
  bool is_leaf(const OctreeCube& c) const { return tree.is_leaf(c.node); }
  template <class F>
  void children(const OctreeCube& c, F&& f) const {
    const std::uint8_t mask = tree.child_mask(c.node);
    const std::int32_t first = tree.children_block(c.node);
    for (int i = 7; i >= 0; --i) {  // the last pushed is the first walked
      const int b = order[i];
      if ((mask >> b) & 1) f(OctreeCube{first + b, c.depth + 1, child_corner(c.corner, c.depth, b), child_index(c.index, b)});
    }
  }
};

// Every node from the root, free and occupied (OctoMap's tree iterator): depth first, a node
// before its children, the children of a node in `order`. `visit(cube)` answers kEnter (its
// children next), kSkip (not them) or kStop (end the walk).
template <class VisitFn>
void walk_nodes(const Octree& tree, VisitFn&& visit, const std::array<std::uint8_t, 8>& order = kSeedChildOrder) {
  if (tree.root() < 0) return;
  depth_first_walk(OctreeNodeView{tree, order}, OctreeCube{tree.root(), 0, OctreeKey{}, 0}, visit,
                   [](const OctreeCube&) { return false; });
}

// f(leaf) for every leaf, free or occupied (pruned ones above depth 16 included), in docs/design.md's order.
template <class F>
void for_each_leaf(const Octree& tree, F&& f) {
  walk_nodes(tree, [&](const OctreeCube& c) {
    if (tree.is_leaf(c.node)) f(leaf_of(tree, c));
    return Visit::kEnter;
  });
}

// f(leaf) for every occupied leaf, in docs/design.md's order.
template <class F>
void for_each_occupied_leaf(const Octree& tree, F&& f) {
  const auto root = occupied_root(tree);
  if (!root) return;
  descend_while(
      tree, *root, [](const OctreeCube&) { return Visit::kEnter; },
      [&](const OctreeCube& c) {
        f(leaf_of(tree, c));
        return false;
      });
}

}  // namespace bvh_collision
