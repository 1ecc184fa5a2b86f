// The depth-first walks of every hierarchy, written once: a BVH, a proxy sphere tree, the
// octree's cubes, and pairs of them (BVH x BVH, sphere tree x sphere tree, BVH x octree) are all
// walked by these two loops. What differs between trees is a view of the tree; what differs
// between queries is their callbacks; the loop, the stack and the stopping rule live here.
//
//   depth_first_walk(view, root, visit, leaf)                     visit(n) -> Visit, leaf(n) -> stop?
//   depth_first_pair_walk(va, vb, ra, rb, visit, leaf, expand)    visit(a, b) -> Visit, leaf(a, b) -> stop?,
//                                                                 expand(a, b, push(a', b'))
//
// A view offers `Node` (a small trivially copyable handle: an index, a cube), `is_leaf(node)` and
// `children(node, f)`, which calls f(child) for each child in push order: the last one pushed is
// walked first. A pair that is not two leaves is opened by the query's `expand` (which side to
// open, in which order: the rule that differs between a BVH pair and a sphere-tree pair), usually
// through a view's children(). The stack is a template parameter (the default lives on the C++
// stack for the usual depths; geometry/traversal_stack.h). Header-only: the callbacks are
// lambdas, inlined into each query's loop.
#pragma once

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

// Depth first over pairs of nodes of two trees from (ra, rb). `visit(a, b)` decides for every
// pair reached; an entered pair of leaves goes to `leaf(a, b)`, which returns true to stop; any
// other entered pair is opened by `expand(a, b, push)`, which pushes the pairs to walk next.
template <template <class> class Stack = DefaultTraversalStack, class ViewA, class ViewB, class VisitFn, class LeafFn,
          class ExpandFn>
void depth_first_pair_walk(const ViewA& va, const ViewB& vb, const typename ViewA::Node& ra, const typename ViewB::Node& rb,
                           VisitFn&& visit, LeafFn&& leaf, ExpandFn&& expand) {
  struct Pair {
    typename ViewA::Node a;
    typename ViewB::Node b;
  };
  Stack<Pair> stack;
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

}  // namespace bvh_collision
