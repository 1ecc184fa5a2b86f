// The walks of the octree's occupied cubes, written once: every query that descends the tree
// alone (a box, a ball, a primitive, a point's nearest cube, a solid's inside) is one of these two
// loops with its own callbacks, in the spirit of OctoMap's leaf iterators with a "descend while
// the predicate holds" test.
//
//   descend_while(tree, start, visit, leaf, children)   visit(cube) -> Visit, leaf(cube) -> stop?
//   nearest_cubes_first(tree, start, bound, leaf, cutoff)
//
// Only occupied cubes are reached (an inner cube is occupied when some cube inside it is).
// Header-only: the callbacks are lambdas, inlined into each query's loop.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "bvh_collision/geometry/traversal_stack.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

// A node of the octree with its cube: depth, the key of its lowest voxel, its seed index.
struct OctreeCube {
  std::int32_t node;
  int depth;
  OctreeKey corner;
  std::uint64_t index;
};

// Every child (a mask of the seed's child bits b: x is bit 2, y bit 1, z bit 0).
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

// Depth first from `start` (an occupied cube): `visit(cube)` decides for every cube reached; an
// entered leaf goes to `leaf(cube)`, which returns true to stop; `children(cube)` masks which
// children of an entered inner cube are reached (a cheap integer range test, say).
template <class VisitFn, class LeafFn, class MaskFn = AllChildren>
void descend_while(const Octree& tree, const OctreeCube& start, VisitFn&& visit, LeafFn&& leaf,
                   MaskFn&& children = {}) {
  TraversalStack<OctreeCube> stack;
  stack.push(start);
  while (!stack.empty()) {
    const OctreeCube c = stack.pop();
    const Visit v = visit(c);
    if (v == Visit::kStop) return;
    if (v == Visit::kSkip) continue;
    if (tree.is_leaf(c.node)) {
      if (leaf(c)) return;
      continue;
    }
    // Highest child bit pushed first, so child 0 is reached first (the seed's order).
    unsigned bits = children(c) & tree.child_mask(c.node);
    const std::int32_t first = tree.children_block(c.node);
    while (bits) {
      const int b = 31 - __builtin_clz(bits);
      bits &= ~(1u << b);
      const std::int32_t child = first + b;
      if (tree.occupied(tree.value(child))) {
        stack.push(OctreeCube{child, c.depth + 1, child_corner(c.corner, c.depth, b), child_index(c.index, b)});
      }
    }
  }
}

// Depth first from `start`, nearest child first, pruned by bounds: a cube whose `bound(cube)` is
// not below `cutoff()` is never entered. `leaf(cube)` lowers the cutoff as it finds answers and
// returns true to stop.
template <class BoundFn, class LeafFn, class CutoffFn>
void nearest_cubes_first(const Octree& tree, const OctreeCube& start, BoundFn&& bound, LeafFn&& leaf,
                         CutoffFn&& cutoff) {
  std::vector<std::pair<double, OctreeCube>> stack{{bound(start), start}}, children;
  while (!stack.empty()) {
    const auto [lower, c] = stack.back();
    stack.pop_back();
    if (!(lower < cutoff())) continue;
    if (tree.is_leaf(c.node)) {
      if (leaf(c)) return;
      continue;
    }
    children.clear();
    for_occupied_children(tree, c, [&](const OctreeCube& child) {
      const double d = bound(child);
      if (d < cutoff()) children.emplace_back(d, child);
    });
    // Nearest on top, so that a small cutoff comes early and prunes the rest.
    std::sort(children.begin(), children.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    stack.insert(stack.end(), children.begin(), children.end());
  }
}

}  // namespace bvh_collision
