// The traversal cores (bvh/traversal.h, octree/cube_walk.h) against brute force: every leaf is
// reached once when nothing is pruned, stopping stops, the bounded walks find the true minimum,
// and the pair walks see every leaf pair. And the robot collision model is built once: copies of
// a checker share it.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <random>
#include <set>

#include "bvh_collision/bvh/traversal.h"
#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/tree_walk.h"
#include "bvh_collision/octree/cube_walk.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(41);
  return r;
}

Bvh<Obb> soup(int n) { return Bvh<Obb>::build(test::triangle_soup(rng(), n, 1.0, 0.1), {BuildMethod::kSah, 2}); }

// The leaf-order triangle indices under a node.
std::vector<int> leaf_triangles(const BvhNode<Obb>& n) {
  std::vector<int> out;
  for (std::int32_t i = n.first; i < n.first + n.count; ++i) out.push_back(i);
  return out;
}

TEST(Traversal, DepthFirstReachesEveryTriangleOnceAndStops) {
  const Bvh<Obb> bvh = soup(300);
  std::multiset<int> seen;
  int visits = 0;
  depth_first(
      bvh, [&](const BvhNode<Obb>&) { return ++visits, Visit::kEnter; },
      [&](const BvhNode<Obb>& n) {
        for (const int i : leaf_triangles(n)) seen.insert(i);
        return false;
      });
  ASSERT_EQ(seen.size(), bvh.triangles().size());
  for (std::size_t i = 0; i < bvh.triangles().size(); ++i) {
    EXPECT_EQ(seen.count(static_cast<int>(i)), 1u);
  }
  EXPECT_EQ(visits, static_cast<int>(bvh.nodes().size()));  // every node once

  int leaves = 0;
  depth_first(bvh, [](const BvhNode<Obb>&) { return Visit::kEnter; }, [&](const BvhNode<Obb>&) { return ++leaves == 3; });
  EXPECT_EQ(leaves, 3) << "a leaf returning true stops the walk";
  int after_stop = 0;
  depth_first(bvh, [&](const BvhNode<Obb>&) { return ++after_stop, Visit::kStop; }, [](const BvhNode<Obb>&) { return false; });
  EXPECT_EQ(after_stop, 1);

  // The tree's depth (a walk too) against recursion.
  const auto& nodes = bvh.nodes();
  std::function<int(std::int32_t)> depth = [&](std::int32_t i) {
    return nodes[i].is_leaf() ? 1 : 1 + std::max(depth(nodes[i].left), depth(nodes[i].right));
  };
  EXPECT_EQ(bvh.depth(), depth(0));
  EXPECT_GT(bvh.depth(), 3);
}

TEST(Traversal, NearestFirstFindsTheClosestTriangle) {
  const Bvh<Obb> bvh = soup(400);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int k = 0; k < 50; ++k) {
    const Vec3 q(u(rng()), u(rng()), u(rng()));
    double truth = std::numeric_limits<double>::infinity();
    for (const Triangle& t : bvh.triangles()) truth = std::min(truth, (closest_point_on_triangle(q, t[0], t[1], t[2]) - q).norm());
    double best = std::numeric_limits<double>::infinity();
    int leaves = 0;
    nearest_first(
        bvh, [&](std::int32_t i) { return (q - center(bvh.nodes()[i].volume)).norm() - bvh.nodes()[i].size; },
        [&](const BvhNode<Obb>& n) {
          ++leaves;
          for (const int i : leaf_triangles(n)) {
            const Triangle& t = bvh.triangles()[i];
            best = std::min(best, (closest_point_on_triangle(q, t[0], t[1], t[2]) - q).norm());
          }
          return false;
        },
        [&] { return best; });
    EXPECT_EQ(best, truth) << k;
    EXPECT_LT(leaves, static_cast<int>(bvh.triangles().size()) / 4) << "the bound prunes";
  }
}

TEST(Traversal, PairWalksSeeEveryLeafPairAndTheBestFirstMinimum) {
  const Bvh<Obb> a = soup(120), b = soup(120);
  const Transform b_in_a = test::random_rotation(rng(), Vec3(1.5, 0.2, 0.1));
  const RelativeFrame f = RelativeFrame::from(b_in_a);
  std::set<std::pair<int, int>> pairs;
  depth_first_pair(
      a, b, [](std::int32_t, std::int32_t) { return Visit::kEnter; },
      [&](const BvhNode<Obb>& na, const BvhNode<Obb>& nb) {
        for (const int i : leaf_triangles(na)) {
          for (const int j : leaf_triangles(nb)) {
            EXPECT_TRUE(pairs.emplace(i, j).second) << "pair reached twice";
          }
        }
        return false;
      });
  EXPECT_EQ(pairs.size(), a.triangles().size() * b.triangles().size());

  double truth = std::numeric_limits<double>::infinity();
  for (const Triangle& ta : a.triangles()) {
    for (const Triangle& tb : b.triangles()) {
      const Triangle carried{{b_in_a * tb[0], b_in_a * tb[1], b_in_a * tb[2]}};
      truth = std::min(truth, triangle_triangle_distance(ta, carried).distance);
    }
  }
  double best = std::numeric_limits<double>::infinity();
  std::size_t leaf_pairs = 0;
  best_first_pair(
      a, b, [&](std::int32_t i, std::int32_t j) { return distance_lower_bound(a.nodes()[i].volume, b.nodes()[j].volume, f); },
      [&](const BvhNode<Obb>& na, const BvhNode<Obb>& nb) {
        ++leaf_pairs;
        for (const int i : leaf_triangles(na)) {
          for (const int j : leaf_triangles(nb)) {
            const Triangle& tb = b.triangles()[j];
            const Triangle carried{{b_in_a * tb[0], b_in_a * tb[1], b_in_a * tb[2]}};
            best = std::min(best, triangle_triangle_distance(a.triangles()[i], carried).distance);
          }
        }
        return false;
      },
      [&] { return best; });
  EXPECT_EQ(best, truth);
  EXPECT_LT(leaf_pairs, pairs.size() / 20) << "the bound prunes";
}

Octree random_tree(double resolution, int voxels) {
  Octree tree(resolution);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < voxels; ++i) {
    if (const auto key = tree.grid().key(Vec3(u(rng()), u(rng()), 0.5 * u(rng())))) {
      for (int k = 0; k < 3; ++k) tree.update(*key, true);
    }
  }
  return tree;
}

// The generic walks themselves (geometry/tree_walk.h) on a toy view: a complete binary tree of
// depth d by heap index. Nothing pruned, every leaf (pair) is reached once, in push order; kSkip
// prunes a subtree, kStop and a leaf's true end the walk.
struct HeapTreeView {
  using Node = int;
  int leaves_from;  // nodes at or beyond this index are leaves
  bool is_leaf(int i) const { return i >= leaves_from; }
  template <class F>
  void children(int i, F&& f) const {
    f(2 * i + 2);  // the right child pushed first, so the left one (2i + 1) is walked first
    f(2 * i + 1);
  }
};

TEST(TreeWalk, EveryLeafAndLeafPairOnceInOrderAndStops) {
  const HeapTreeView view{7};  // 15 nodes, leaves 7..14
  std::vector<int> leaves;
  depth_first_walk(view, 0, [](int) { return Visit::kEnter; }, [&](int i) {
    leaves.push_back(i);
    return false;
  });
  EXPECT_EQ(leaves, (std::vector<int>{7, 8, 9, 10, 11, 12, 13, 14}));
  leaves.clear();
  depth_first_walk(view, 0, [](int i) { return i == 1 ? Visit::kSkip : Visit::kEnter; }, [&](int i) {
    leaves.push_back(i);
    return i == 12;
  });
  EXPECT_EQ(leaves, (std::vector<int>{11, 12}));
  std::set<std::pair<int, int>> pairs;
  int visits = 0;
  auto expand = [&](int a, int b, auto&& push) {
    if (!view.is_leaf(a)) {
      view.children(a, [&](int c) { push(c, b); });
    } else {
      view.children(b, [&](int c) { push(a, c); });
    }
  };
  depth_first_pair_walk(view, view, 0, 0, [&](int, int) { return ++visits, Visit::kEnter; }, [&](int a, int b) {
    EXPECT_TRUE(pairs.insert({a, b}).second);
    return false;
  }, expand);
  EXPECT_EQ(pairs.size(), 64u);
  EXPECT_EQ(visits, 15 + 8 * 14);  // a's tree, then b's below each leaf of a
  visits = 0;
  depth_first_pair_walk(view, view, 0, 0, [&](int, int) { return ++visits == 5 ? Visit::kStop : Visit::kEnter; },
                        [](int, int) { return false; }, expand);
  EXPECT_EQ(visits, 5);
}

// The stackless walk of a depth-first tree with skip indices (the proxy sphere trees) against the
// stack walk of the same tree: the same nodes in the same order, pruning and stopping alike.
TEST(TreeWalk, SkipWalkVisitsAsTheStackWalk) {
  const HeapTreeView view{7};
  // The heap tree laid out depth first, children in order: pre[k] is the heap node at position k.
  std::vector<int> pre, skip;
  const auto lay = [&](const auto& self, int node) -> void {
    const std::size_t at = pre.size();
    pre.push_back(node);
    skip.push_back(0);
    if (!view.is_leaf(node)) self(self, 2 * node + 1), self(self, 2 * node + 2);
    skip[at] = static_cast<int>(pre.size());
  };
  lay(lay, 0);
  ASSERT_EQ(pre.size(), 15u);
  for (const int pruned : {-1, 1, 5, 12}) {
    for (const int stop_at : {-1, 9, 13}) {
      std::vector<int> by_stack, by_skip;
      // The stack walk takes the left child first: the same preorder.
      depth_first_walk(view, 0, [&](int i) {
        by_stack.push_back(i);
        if (i == stop_at) return Visit::kStop;
        return i == pruned ? Visit::kSkip : Visit::kEnter;
      }, [](int) { return false; });
      skip_walk(15, [&](std::int32_t k) { return skip[k]; }, [&](std::int32_t k, bool leaf) {
        EXPECT_EQ(leaf, view.is_leaf(pre[k]));
        by_skip.push_back(pre[k]);
        if (pre[k] == stop_at) return Visit::kStop;
        return pre[k] == pruned ? Visit::kSkip : Visit::kEnter;
      });
      EXPECT_EQ(by_skip, by_stack) << "pruned " << pruned << " stop " << stop_at;
    }
  }
  // In order: a whole walk is the depth-first (pre)order itself.
  std::vector<int> all;
  skip_walk(15, [&](std::int32_t k) { return skip[k]; }, [&](std::int32_t k, bool) { return all.push_back(pre[k]), Visit::kEnter; });
  EXPECT_EQ(all, pre);
  EXPECT_EQ(pre, (std::vector<int>{0, 1, 3, 7, 8, 4, 9, 10, 2, 5, 11, 12, 6, 13, 14}));
}

TEST(CubeWalk, DescendWhileReachesEveryOccupiedLeafAndNearestFirstFindsTheClosest) {
  const Octree tree = random_tree(0.05, 400);
  std::set<std::uint64_t> occupied;
  for (const Octree::Leaf& l : tree.leaves()) {
    if (tree.occupied(l.log_odds)) occupied.insert(l.index);
  }
  ASSERT_GT(occupied.size(), 100u);
  const auto root = occupied_root(tree);
  ASSERT_TRUE(root);
  std::set<std::uint64_t> walked;
  descend_while(
      tree, *root, [](const OctreeCube&) { return Visit::kEnter; },
      [&](const OctreeCube& c) {
        EXPECT_TRUE(walked.insert(c.index).second);
        return false;
      });
  EXPECT_EQ(walked, occupied);

  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (int k = 0; k < 50; ++k) {
    const Vec3 p(u(rng()), u(rng()), u(rng()));
    auto gap = [&](const Vec3& lo, double size) {
      return (p - p.cwiseMax(lo).cwiseMin(lo + Vec3::Constant(size))).norm();
    };
    double truth = std::numeric_limits<double>::infinity();
    for (const Octree::Leaf& l : tree.leaves()) {
      if (tree.occupied(l.log_odds)) truth = std::min(truth, gap(tree.cube_min(l.key), tree.cube_size(l.depth)));
    }
    double best = std::numeric_limits<double>::infinity();
    nearest_cubes_first(
        tree, *root, [&](const OctreeCube& c) { return gap(tree.cube_min(c.corner), tree.cube_size(c.depth)); },
        [&](const OctreeCube& c) {
          best = std::min(best, gap(tree.cube_min(c.corner), tree.cube_size(c.depth)));
          return false;
        },
        [&] { return best; });
    EXPECT_EQ(best, truth) << k;
  }
}

// The octree's own walk (leaves, the .ot node stream): every node once, a parent before its
// children, children in the order asked; each leaf is what find() says of its voxel; kSkip prunes
// and kStop stops.
TEST(CubeWalk, WalkNodesVisitsEveryNodeOnceInTheOrderAsked) {
  const Octree tree = random_tree(0.05, 400);
  for (const auto* order : {&kSeedChildOrder, &kOctomapChildOrder}) {
    std::set<std::int32_t> seen;
    std::vector<OctreeCube> path;  // the cubes from the root to the last one visited
    std::size_t leaves = 0;
    walk_nodes(
        tree,
        [&](const OctreeCube& c) {
          EXPECT_TRUE(seen.insert(c.node).second);
          // Pre-order: the parent is on the path, and an earlier sibling comes earlier in `order`.
          while (!path.empty() && path.back().depth >= c.depth) {
            const OctreeCube left = path.back();
            path.pop_back();
            if (left.depth == c.depth) {
              const auto rank = [&](const OctreeCube& x) {
                return std::find(order->begin(), order->end(), static_cast<std::uint8_t>((x.index - 1) % 8)) - order->begin();
              };
              EXPECT_LT(rank(left), rank(c));
            }
          }
          EXPECT_EQ(static_cast<int>(path.size()), c.depth);
          if (!path.empty()) {
            EXPECT_EQ((c.index - 1) / 8, path.back().index);
          }
          path.push_back(c);
          if (tree.is_leaf(c.node)) {
            ++leaves;
            const auto found = tree.find(c.corner);
            EXPECT_TRUE(found && found->depth == c.depth && found->index == c.index && found->log_odds == tree.value(c.node));
          }
          return Visit::kEnter;
        },
        *order);
    EXPECT_EQ(seen.size(), tree.node_count());
    EXPECT_GT(leaves, 100u);
  }
  // kSkip below the root's children: the root and its children only; kStop at the fifth node.
  std::size_t visited = 0;
  walk_nodes(tree, [&](const OctreeCube& c) { ++visited; return c.depth == 1 ? Visit::kSkip : Visit::kEnter; });
  EXPECT_EQ(visited, 1u + __builtin_popcount(tree.child_mask(tree.root())));
  visited = 0;
  walk_nodes(tree, [&](const OctreeCube&) { return ++visited == 5 ? Visit::kStop : Visit::kEnter; });
  EXPECT_EQ(visited, 5u);
}

TEST(RobotCollisionModel, BuiltOnceAndSharedByCheckerCopies) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const CollisionChecker copy = checker;  // NOLINT: the copy is the point
  EXPECT_EQ(&checker.collision_model(), &copy.collision_model());
  const RobotCollisionModel& m = checker.collision_model();
  EXPECT_EQ(m.shapes().size(), checker.model().links().size());
  EXPECT_EQ(m.checked_pairs(), checker.checked_pairs());
  EXPECT_EQ(m.meshes().size(), checker.built_meshes());
  std::vector<double> state(checker.model().variable_count(), 0.1);
  EXPECT_EQ(checker.check_self(state.data()).collision, copy.check_self(state.data()).collision);
}

}  // namespace
}  // namespace bvh_collision
