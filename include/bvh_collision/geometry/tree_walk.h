// The depth-first walks of every hierarchy, written once: a BVH, a proxy sphere tree, the
// octree's cubes, and pairs of them (BVH x BVH, sphere tree x sphere tree, BVH x octree) are all
// walked by these two loops. What differs between trees is a view of the tree; what differs
// between queries is their callbacks; the loop, the stack and the stopping rule live here.
//
//   depth_first_walk(view, root, visit, leaf)                     visit(n) -> Visit, leaf(n) -> stop?
//   depth_first_pair_walk(va, vb, ra, rb, visit, leaf, expand)    visit(a, b) -> Visit, leaf(a, b) -> stop?,
//                                                                 expand(a, b, push(a', b'))
//   nearest_first_walk(view, root, bound, leaf, cutoff)           bound(n) -> double, cutoff() -> double
//   nearest_first_pair_walk(va, vb, ra, rb, root_bound, bound, leaf, expand, cutoff)
//   skip_walk(count, skip, visit)                                 visit(i, leaf) -> Visit (no stack)
//
// The nearest-first walks are the bounded ones (distances): a node (pair) whose bound is not
// below cutoff() is never entered, and of an entered node's children the nearest is walked
// first, so that a small cutoff comes early and prunes the rest (cutoff() may fall as the leaves
// find answers). Their views also give kMaxChildren, the most children a node has.
//
// A view offers `Node` (a small trivially copyable handle: an index, a cube), `is_leaf(node)` and
// `children(node, f)`, which calls f(child) for each child in push order: the last one pushed is
// walked first. A pair that is not two leaves is opened by the query's `expand` (which side to
// open, in which order: the rule that differs between a BVH pair and a sphere-tree pair), usually
// through a view's children(). The stack is a template parameter (the default lives on the C++
// stack for the usual depths; geometry/traversal_stack.h). Header-only: the callbacks are
// lambdas, inlined into each query's loop.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>

#include "bvh_collision/geometry/traversal_stack.h"

namespace bvh_collision {

template <class T>
using DefaultTraversalStack = TraversalStack<T>;

// Depth first from `root`. `visit(node)` decides for every node reached; an entered leaf goes to
// `leaf(node)`, which returns true to stop; an entered inner node's children are walked next.
template <template <class> class Stack = DefaultTraversalStack, class View, class VisitFn, class LeafFn>
void depth_first_walk(const View& view, const typename View::Node& root, VisitFn&& visit, LeafFn&& leaf) {
  using Node = typename View::Node;
  Stack<Node> stack;
  stack.push(root);
  while (!stack.empty()) {
    const Node n = stack.pop();
    const Visit v = visit(n);
    if (v == Visit::kStop) return;
    if (v == Visit::kSkip) continue;
    if (view.is_leaf(n)) {
      if (leaf(n)) return;
      continue;
    }
    view.children(n, [&](const Node& c) { stack.push(c); });
  }
}

// Depth first without a stack, for a tree stored in depth-first order where node i knows
// `skip(i)`, the index just past its subtree (a leaf: i + 1; the proxy sphere trees). `visit(i,
// leaf)` decides for each node reached: kSkip jumps past its subtree, kEnter goes on to the next
// node in order (into the subtree; for a leaf the same as kSkip), kStop ends the walk.
template <class SkipFn, class VisitFn>
void skip_walk(std::int32_t count, SkipFn&& skip, VisitFn&& visit) {
  for (std::int32_t i = 0; i < count;) {
    const std::int32_t past = skip(i);
    const Visit v = visit(i, past == i + 1);
    if (v == Visit::kStop) return;
    i = v == Visit::kSkip ? past : i + 1;
  }
}

// A pair of nodes of two trees, as the pair walks keep them.
template <class A, class B>
struct NodePair {
  A a;
  B b;
};

// Depth first over pairs of nodes of two trees from (ra, rb). `visit(a, b)` decides for every
// pair reached; an entered pair of leaves goes to `leaf(a, b)`, which returns true to stop; any
// other entered pair is opened by `expand(a, b, push)`, which pushes the pairs to walk next.
// depth_first_pair_walk_on walks on a stack the caller holds (push, pop, empty over
// NodePair<ViewA::Node, ViewB::Node>: memory it already has, as the SIMD batch kernel's).
template <class StackT, class ViewA, class ViewB, class VisitFn, class LeafFn, class ExpandFn>
void depth_first_pair_walk_on(StackT& stack, const ViewA& va, const ViewB& vb, const typename ViewA::Node& ra,
                              const typename ViewB::Node& rb, VisitFn&& visit, LeafFn&& leaf, ExpandFn&& expand) {
  using Pair = NodePair<typename ViewA::Node, typename ViewB::Node>;
  stack.push(Pair{ra, rb});
  while (!stack.empty()) {
    const Pair p = stack.pop();
    const Visit v = visit(p.a, p.b);
    if (v == Visit::kStop) return;
    if (v == Visit::kSkip) continue;
    if (va.is_leaf(p.a) && vb.is_leaf(p.b)) {
      if (leaf(p.a, p.b)) return;
      continue;
    }
    expand(p.a, p.b, [&](const typename ViewA::Node& a, const typename ViewB::Node& b) { stack.push(Pair{a, b}); });
  }
}

template <template <class> class Stack = DefaultTraversalStack, class ViewA, class ViewB, class VisitFn, class LeafFn,
          class ExpandFn>
void depth_first_pair_walk(const ViewA& va, const ViewB& vb, const typename ViewA::Node& ra, const typename ViewB::Node& rb,
                           VisitFn&& visit, LeafFn&& leaf, ExpandFn&& expand) {
  Stack<NodePair<typename ViewA::Node, typename ViewB::Node>> stack;
  depth_first_pair_walk_on(stack, va, vb, ra, rb, std::forward<VisitFn>(visit), std::forward<LeafFn>(leaf),
                           std::forward<ExpandFn>(expand));
}

namespace detail {

// The children of an entered node, kept below `limit` and pushed farthest first (the nearest on
// top). At most N of them.
template <class Entry, std::size_t N>
class NearestFirstChildren {
 public:
  void add(const Entry& e, double limit) {
    if (e.bound < limit) entries_[count_++] = e;
  }
  template <class Stack>
  void push_to(Stack& stack) {
    // Insertion sort by bound, farthest first: at most a few entries.
    for (std::size_t i = 1; i < count_; ++i) {
      for (std::size_t j = i; j > 0 && entries_[j - 1].bound < entries_[j].bound; --j) std::swap(entries_[j - 1], entries_[j]);
    }
    for (std::size_t i = 0; i < count_; ++i) stack.push(entries_[i]);
  }

 private:
  Entry entries_[N];
  std::size_t count_ = 0;
};

}  // namespace detail

// Nearest first from `root`, pruned by `bound(node)` against `cutoff()`; a leaf goes to
// `leaf(node)`, which may lower the cutoff and returns true to stop.
template <template <class> class Stack = DefaultTraversalStack, class View, class BoundFn, class LeafFn, class CutoffFn>
void nearest_first_walk(const View& view, const typename View::Node& root, BoundFn&& bound, LeafFn&& leaf, CutoffFn&& cutoff) {
  struct Entry {
    typename View::Node node;
    double bound;
  };
  Stack<Entry> stack;
  stack.push(Entry{root, bound(root)});
  while (!stack.empty()) {
    const Entry e = stack.pop();
    if (!(e.bound < cutoff())) continue;
    if (view.is_leaf(e.node)) {
      if (leaf(e.node)) return;
      continue;
    }
    detail::NearestFirstChildren<Entry, View::kMaxChildren> children;
    const double limit = cutoff();
    view.children(e.node, [&](const typename View::Node& c) { children.add(Entry{c, bound(c)}, limit); });
    children.push_to(stack);
  }
}

// Nearest first over pairs from (ra, rb), whose bound is `root_bound`: `expand(a, b, push)` names
// the child pairs of an entered pair that is not two leaves, each bounded by `bound(a', b')` and
// walked nearest first; a pair of leaves goes to `leaf(a, b)` (true: stop).
template <template <class> class Stack = DefaultTraversalStack, class ViewA, class ViewB, class BoundFn, class LeafFn,
          class ExpandFn, class CutoffFn>
void nearest_first_pair_walk(const ViewA& va, const ViewB& vb, const typename ViewA::Node& ra, const typename ViewB::Node& rb,
                             double root_bound, BoundFn&& bound, LeafFn&& leaf, ExpandFn&& expand, CutoffFn&& cutoff) {
  struct Entry {
    typename ViewA::Node a;
    typename ViewB::Node b;
    double bound;
  };
  constexpr std::size_t kChildren = ViewA::kMaxChildren > ViewB::kMaxChildren ? ViewA::kMaxChildren : ViewB::kMaxChildren;
  Stack<Entry> stack;
  stack.push(Entry{ra, rb, root_bound});
  while (!stack.empty()) {
    const Entry e = stack.pop();
    if (!(e.bound < cutoff())) continue;
    if (va.is_leaf(e.a) && vb.is_leaf(e.b)) {
      if (leaf(e.a, e.b)) return;
      continue;
    }
    detail::NearestFirstChildren<Entry, kChildren> children;
    const double limit = cutoff();
    expand(e.a, e.b, [&](const typename ViewA::Node& a, const typename ViewB::Node& b) {
      children.add(Entry{a, b, bound(a, b)}, limit);
    });
    children.push_to(stack);
  }
}

}  // namespace bvh_collision
