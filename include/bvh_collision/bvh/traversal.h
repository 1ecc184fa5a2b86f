// The traversals of bounding volume hierarchies, written once: every query over one hierarchy or
// a pair of them (collision, distance, containment, rays, a primitive against a mesh) is one of
// these four with its own callbacks, so the order of descent, the stack and the pruning rule live
// here and nowhere else. The two depth-first ones are the generic walks of geometry/tree_walk.h
// over a BvhView, and so is nearest_first; best_first_pair keeps a heap (always the nearest pair
// of all, not of one node's children).
//
//   depth_first(bvh, visit, leaf, left_first)          visit(node) -> Visit, leaf(node) -> stop?
//   nearest_first(bvh, bound, leaf, cutoff)            bound(i) -> double, cutoff() -> double
//   depth_first_pair(a, b, visit, leaf, left_first)    visit(ia, ib) -> Visit, leaf(na, nb) -> stop?
//   best_first_pair(a, b, bound, leaf, cutoff)         bound(ia, ib) -> double
//
// Pruning is the callbacks' business: a `visit` says kSkip only when nothing below can matter
// (the volume tests of bvh/volumes/ are conservative by geometry/safety_margin.h), and a `bound`
// never exceeds what the leaves below could give. The bounded traversals prune a node whose
// bound is not below `cutoff()` (cutoff() may fall as the leaves find answers).
// Header-only: the callbacks are lambdas, inlined into each query's loop.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/geometry/traversal_stack.h"
#include "bvh_collision/geometry/tree_walk.h"

namespace bvh_collision {

// The default child order: left first.
struct LeftFirst {
  template <class... Nodes>
  bool operator()(const Nodes&...) const { return true; }
};

// Of a node pair, which to split: the larger volume, unless it is a leaf.
template <class BV>
bool split_first_of_pair(const BvhNode<BV>& na, const BvhNode<BV>& nb) {
  if (nb.is_leaf()) return true;
  if (na.is_leaf()) return false;
  return na.size >= nb.size;
}

// A BVH as geometry/tree_walk.h walks it: nodes by index, `left_first(node)` ordering an inner
// node's children.
template <class BV, class OrderFn = LeftFirst>
struct BvhView {
  using Node = std::int32_t;
  static constexpr std::size_t kMaxChildren = 2;
  const Bvh<BV>& bvh;
  OrderFn left_first;
  bool is_leaf(Node i) const { return bvh.nodes()[i].is_leaf(); }
  template <class F>
  void children(Node i, F&& f) const {
    const BvhNode<BV>& n = bvh.nodes()[i];
    const bool left = left_first(n);
    f(left ? n.right : n.left);  // the first child is walked next
    f(left ? n.left : n.right);
  }
};

// Depth first from the root. `visit(node)` decides for every node reached; an entered leaf goes
// to `leaf(node)`, which returns true to stop. `left_first(node)` orders an inner node's children.
template <class BV, class VisitFn, class LeafFn, class OrderFn = LeftFirst>
void depth_first(const Bvh<BV>& bvh, VisitFn&& visit, LeafFn&& leaf, OrderFn&& left_first = {}) {
  if (bvh.empty()) return;
  const auto& nodes = bvh.nodes();
  const BvhView<BV, OrderFn&> view{bvh, left_first};
  depth_first_walk(
      view, 0, [&](std::int32_t i) { return visit(nodes[i]); }, [&](std::int32_t i) { return leaf(nodes[i]); });
}

// Depth first, nearer child first, pruned by bounds: a node whose `bound(index)` is not below
// `cutoff()` is never entered. `leaf(node)` lowers the cutoff as it finds answers and returns
// true to stop. The nearest-first order makes a small cutoff come early, at the cost of no heap.
template <class BV, class BoundFn, class LeafFn, class CutoffFn>
void nearest_first(const Bvh<BV>& bvh, BoundFn&& bound, LeafFn&& leaf, CutoffFn&& cutoff) {
  if (bvh.empty()) return;
  const auto& nodes = bvh.nodes();
  nearest_first_walk(BvhView<BV>{bvh, LeftFirst{}}, 0, bound, [&](std::int32_t i) { return leaf(nodes[i]); }, cutoff);
}

// Depth first over the pairs of two hierarchies from their roots. `visit(ia, ib)` decides for
// every pair reached; an entered leaf pair goes to `leaf(na, nb)`, which returns true to stop.
// An inner pair splits the larger volume (split_first_of_pair); `left_first(na, nb, split_a)`
// orders the two child pairs.
template <class BV, class VisitFn, class LeafFn, class OrderFn = LeftFirst>
void depth_first_pair(const Bvh<BV>& a, const Bvh<BV>& b, VisitFn&& visit, LeafFn&& leaf, OrderFn&& left_first = {}) {
  if (a.empty() || b.empty()) return;
  const auto& nodes_a = a.nodes();
  const auto& nodes_b = b.nodes();
  depth_first_pair_walk(
      BvhView<BV>{a, LeftFirst{}}, BvhView<BV>{b, LeftFirst{}}, 0, 0, visit,
      [&](std::int32_t ia, std::int32_t ib) { return leaf(nodes_a[ia], nodes_b[ib]); },
      [&](std::int32_t ia, std::int32_t ib, auto&& push) {
        const BvhNode<BV>& na = nodes_a[ia];
        const BvhNode<BV>& nb = nodes_b[ib];
        const bool split_a = split_first_of_pair(na, nb);
        const BvhNode<BV>& split = split_a ? na : nb;
        const bool left = left_first(na, nb, split_a);
        const std::int32_t first = left ? split.left : split.right, second = left ? split.right : split.left;
        split_a ? push(second, ib) : push(ia, second);  // the first is walked next
        split_a ? push(first, ib) : push(ia, first);
      });
}

// Best first over the pairs of two hierarchies: always expands the pair with the smallest
// `bound(ia, ib)` (a min-heap), and ends when that bound is not below `cutoff()`: every pair left
// is then at least as far. `leaf(na, nb)` lowers the cutoff and returns true to stop.
template <class BV, class BoundFn, class LeafFn, class CutoffFn>
void best_first_pair(const Bvh<BV>& a, const Bvh<BV>& b, BoundFn&& bound, LeafFn&& leaf, CutoffFn&& cutoff) {
  if (a.empty() || b.empty()) return;
  struct Entry {
    std::int32_t a, b;
    double bound;
    bool operator<(const Entry& o) const { return bound > o.bound; }  // smallest on top
  };
  // One heap per thread, reused: a query allocates nothing once warm.
  thread_local std::vector<Entry> heap;
  heap.clear();
  heap.push_back({0, 0, bound(0, 0)});
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end());
    const Entry e = heap.back();
    heap.pop_back();
    if (!(e.bound < cutoff())) return;
    const BvhNode<BV>& na = a.nodes()[e.a];
    const BvhNode<BV>& nb = b.nodes()[e.b];
    if (na.is_leaf() && nb.is_leaf()) {
      if (leaf(na, nb)) return;
      continue;
    }
    const bool split_a = split_first_of_pair(na, nb);
    const BvhNode<BV>& split = split_a ? na : nb;
    for (const std::int32_t child : {split.left, split.right}) {
      const Entry c = split_a ? Entry{child, e.b, bound(child, e.b)} : Entry{e.a, child, bound(e.a, child)};
      if (c.bound < cutoff()) {
        heap.push_back(c);
        std::push_heap(heap.begin(), heap.end());
      }
    }
  }
}

}  // namespace bvh_collision
