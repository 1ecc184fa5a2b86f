// The traversals of bounding volume hierarchies, written once: every query over one hierarchy or
// a pair of them (collision, distance, containment, rays, a primitive against a mesh) is one of
// these four loops with its own callbacks, so the order of descent, the stack and the pruning
// rule live here and nowhere else.
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
#include <cstdint>
#include <vector>

#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/geometry/traversal_stack.h"

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

// Depth first from the root. `visit(node)` decides for every node reached; an entered leaf goes
// to `leaf(node)`, which returns true to stop. `left_first(node)` orders an inner node's children.
template <class BV, class VisitFn, class LeafFn, class OrderFn = LeftFirst>
void depth_first(const Bvh<BV>& bvh, VisitFn&& visit, LeafFn&& leaf, OrderFn&& left_first = {}) {
  if (bvh.empty()) return;
  TraversalStack<std::int32_t> stack;
  stack.push(0);
  while (!stack.empty()) {
    const BvhNode<BV>& n = bvh.nodes()[stack.pop()];
    const Visit v = visit(n);
    if (v == Visit::kStop) return;
    if (v == Visit::kSkip) continue;
    if (n.is_leaf()) {
      if (leaf(n)) return;
      continue;
    }
    const bool left = left_first(n);
    stack.push(left ? n.right : n.left);  // the first child is popped next
    stack.push(left ? n.left : n.right);
  }
}

// Depth first, nearer child first, pruned by bounds: a node whose `bound(index)` is not below
// `cutoff()` is never entered. `leaf(node)` lowers the cutoff as it finds answers and returns
// true to stop. The nearest-first order makes a small cutoff come early, at the cost of no heap.
template <class BV, class BoundFn, class LeafFn, class CutoffFn>
void nearest_first(const Bvh<BV>& bvh, BoundFn&& bound, LeafFn&& leaf, CutoffFn&& cutoff) {
  if (bvh.empty()) return;
  struct Entry {
    std::int32_t node;
    double bound;
  };
  TraversalStack<Entry> stack;
  stack.push({0, bound(0)});
  while (!stack.empty()) {
    const Entry e = stack.pop();
    if (!(e.bound < cutoff())) continue;
    const BvhNode<BV>& n = bvh.nodes()[e.node];
    if (n.is_leaf()) {
      if (leaf(n)) return;
      continue;
    }
    Entry far{n.left, bound(n.left)}, near{n.right, bound(n.right)};
    if (far.bound < near.bound) std::swap(far, near);
    const double limit = cutoff();
    if (far.bound < limit) stack.push(far);
    if (near.bound < limit) stack.push(near);
  }
}

// Depth first over the pairs of two hierarchies from their roots. `visit(ia, ib)` decides for
// every pair reached; an entered leaf pair goes to `leaf(na, nb)`, which returns true to stop.
// An inner pair splits the larger volume (split_first_of_pair); `left_first(na, nb, split_a)`
// orders the two child pairs.
template <class BV, class VisitFn, class LeafFn, class OrderFn = LeftFirst>
void depth_first_pair(const Bvh<BV>& a, const Bvh<BV>& b, VisitFn&& visit, LeafFn&& leaf, OrderFn&& left_first = {}) {
  if (a.empty() || b.empty()) return;
  struct Pair {
    std::int32_t a, b;
  };
  TraversalStack<Pair> stack;
  stack.push({0, 0});
  while (!stack.empty()) {
    const Pair p = stack.pop();
    const Visit v = visit(p.a, p.b);
    if (v == Visit::kStop) return;
    if (v == Visit::kSkip) continue;
    const BvhNode<BV>& na = a.nodes()[p.a];
    const BvhNode<BV>& nb = b.nodes()[p.b];
    if (na.is_leaf() && nb.is_leaf()) {
      if (leaf(na, nb)) return;
      continue;
    }
    const bool split_a = split_first_of_pair(na, nb);
    const BvhNode<BV>& split = split_a ? na : nb;
    const bool left = left_first(na, nb, split_a);
    const std::int32_t first = left ? split.left : split.right, second = left ? split.right : split.left;
    stack.push(split_a ? Pair{second, p.b} : Pair{p.a, second});  // the first is popped next
    stack.push(split_a ? Pair{first, p.b} : Pair{p.a, first});
  }
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
