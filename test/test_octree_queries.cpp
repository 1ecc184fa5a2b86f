// Octree queries against brute force over every leaf (point location, boxes, spheres, rays), and
// clearing a box. Built into test_octree (octree_fixtures.h).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>
#include <vector>

#include "bvh_collision/octree/octree.h"
#include "bvh_collision/octree/scan.h"
#include "octree_fixtures.h"

namespace bvh_collision {
namespace {

using test::random_scan;
using test::rng;

// A tree with occupied, free and pruned nodes to query: scans of a random scene.
Octree scanned_tree(double resolution) {
  Octree tree(resolution);
  for (int s = 0; s < 3; ++s) {
    const ScanPoint origin(0.3f * s, 0.0f, 1.0f);
    insert_scan(tree, random_scan(origin, 3000, 1.5), origin);
  }
  // A solid block, so that pruned occupied nodes exist.
  std::vector<ScanPoint> block;
  for (float x = 0.4f; x < 0.79f; x += 0.01f)
    for (float y = -0.2f; y < 0.19f; y += 0.01f)
      for (float z = 0.f; z < 0.39f; z += 0.01f) block.emplace_back(x, y, z);
  for (int i = 0; i < 6; ++i) insert_points(tree, block);  // up to the clamp: equal, pruned
  return tree;
}

struct CubeBounds {
  Vec3 lo, hi;
};
CubeBounds bounds(const Octree& tree, const Octree::Leaf& l) {
  const Vec3 lo = tree.cube_min(l.key);
  return {lo, lo + Vec3::Constant(tree.cube_size(l.depth))};
}

std::vector<Octree::Leaf> occupied_leaves(const Octree& tree) {
  std::vector<Octree::Leaf> out;
  for (const auto& l : tree.leaves()) {
    if (tree.occupied(l.log_odds)) out.push_back(l);
  }
  return out;
}

std::set<std::uint64_t> indices(const std::vector<Octree::Leaf>& leaves) {
  std::set<std::uint64_t> s;
  for (const auto& l : leaves) s.insert(l.index);
  return s;
}

// Point location, box and sphere overlap against brute force over every leaf.
TEST(OctreeQueries, AgainstBruteForce) {
  const Octree tree = scanned_tree(0.04);
  const auto all = tree.leaves();
  const auto occupied = occupied_leaves(tree);
  int pruned_occupied = 0;
  for (const auto& l : occupied) pruned_occupied += l.depth < kOctreeDepth;
  ASSERT_GT(pruned_occupied, 0);
  std::uniform_real_distribution<double> u(-1.5, 1.5), r(0.0, 0.4);
  int located = 0, box_hits = 0, sphere_hits = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 p(u(rng()), u(rng()), u(rng()) * 0.7 + 0.5);
    // locate: the leaf whose cube holds p (half-open, the positive-side convention).
    const auto found = tree.locate(p);
    std::optional<Octree::Leaf> expected;
    const OctreeKey key = *tree.grid().key(p);
    for (const auto& l : all) {
      const int span = 1 << (kOctreeDepth - l.depth);
      bool in = true;
      for (int a = 0; a < 3; ++a) in = in && key.k[a] >= l.key.k[a] && key.k[a] < l.key.k[a] + span;
      if (in) expected = l;
    }
    ASSERT_EQ(found.has_value(), expected.has_value());
    if (found) {
      ++located;
      EXPECT_EQ(found->index, expected->index);
      EXPECT_EQ(found->depth, expected->depth);
      EXPECT_EQ(found->key, expected->key);
      EXPECT_EQ(found->index, node_index(key, found->depth));
    }
    // Box (possibly flat) and sphere against every occupied leaf's cube.
    const Vec3 half(r(rng()), r(rng()), i % 7 == 0 ? 0.0 : r(rng()));
    std::vector<Octree::Leaf> in_box, in_sphere;
    const double radius = r(rng());
    for (const auto& l : occupied) {
      const CubeBounds c = bounds(tree, l);
      if ((c.lo.array() <= (p + half).array()).all() && ((p - half).array() <= c.hi.array()).all()) in_box.push_back(l);
      const Vec3 nearest = p.cwiseMax(c.lo).cwiseMin(c.hi);
      if ((nearest - p).squaredNorm() <= radius * radius) in_sphere.push_back(l);
    }
    EXPECT_EQ(indices(tree.occupied_in_box(p - half, p + half)), indices(in_box));
    EXPECT_EQ(indices(tree.occupied_in_sphere(p, radius)), indices(in_sphere));
    EXPECT_EQ(tree.occupied_in_sphere(p, radius, true).size(), in_sphere.empty() ? 0u : 1u);
    box_hits += !in_box.empty();
    sphere_hits += !in_sphere.empty();
  }
  EXPECT_GT(located, 50);
  EXPECT_GT(box_hits, 30);
  EXPECT_GT(sphere_hits, 30);
}

// A box that touches a cube's face only (the boundary counts), exactly on the voxel grid.
TEST(OctreeQueries, TouchingBoxesAndSpheres) {
  Octree tree(0.5);
  tree.update(*tree.grid().key(Vec3(0.25, 0.25, 0.25)), true);  // the cube [0, 0.5]^3
  EXPECT_EQ(tree.occupied_in_box(Vec3(0.5, 0.1, 0.1), Vec3(1.0, 0.2, 0.2)).size(), 1u);
  EXPECT_EQ(tree.occupied_in_box(Vec3(-1.0, 0.1, 0.1), Vec3(0.0, 0.2, 0.2)).size(), 1u);
  EXPECT_EQ(tree.occupied_in_box(Vec3(0.51, 0.1, 0.1), Vec3(1.0, 0.2, 0.2)).size(), 0u);
  EXPECT_EQ(tree.occupied_in_sphere(Vec3(1.0, 0.25, 0.25), 0.5).size(), 1u);
  EXPECT_EQ(tree.occupied_in_sphere(Vec3(1.0, 0.25, 0.25), 0.49).size(), 0u);
  EXPECT_EQ(tree.occupied_in_sphere(Vec3(0.25, 0.25, 0.25), 0.0).size(), 1u);  // a point inside
}

// Ray casting against the nearest entry into any occupied cube, found by clipping the ray to
// every cube.
TEST(OctreeQueries, RayAgainstBruteForce) {
  const Octree tree = scanned_tree(0.05);
  const auto occupied = occupied_leaves(tree);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 origin(u(rng()), u(rng()), 1.0 + 0.5 * u(rng()));
    Vec3 direction(u(rng()), u(rng()), u(rng()) - 0.5);
    if (i % 10 == 0) direction = Vec3(0, 0, -1);  // axis-parallel: zero components
    const Vec3 d = direction.normalized();
    double best = std::numeric_limits<double>::infinity();
    for (const auto& l : occupied) {
      const CubeBounds c = bounds(tree, l);
      double t_in = 0.0, t_out = 3.0;
      for (int a = 0; a < 3 && t_in <= t_out; ++a) {
        if (d[a] == 0.0) {
          if (origin[a] < c.lo[a] || origin[a] > c.hi[a]) t_in = 1e9;
          continue;
        }
        const double t1 = (c.lo[a] - origin[a]) / d[a], t2 = (c.hi[a] - origin[a]) / d[a];
        t_in = std::max(t_in, std::min(t1, t2));
        t_out = std::min(t_out, std::max(t1, t2));
      }
      if (t_in <= t_out) best = std::min(best, t_in);
    }
    const auto hit = tree.cast_ray(origin, direction, 3.0);
    ASSERT_EQ(hit.has_value(), std::isfinite(best)) << i;
    if (hit) {
      ++hits;
      EXPECT_NEAR(hit->distance, best, 1e-12);
      EXPECT_NEAR((hit->point - (origin + best * d)).norm(), 0.0, 1e-9);
      EXPECT_TRUE(tree.occupied(hit->leaf.log_odds));
    }
  }
  EXPECT_GT(hits, 50);
  EXPECT_FALSE(tree.cast_ray(Vec3::Zero(), Vec3::Zero(), 1.0).has_value());
}

// Clearing a box forgets exactly the voxels whose keys lie in it and keeps every other value;
// inner nodes still hold the maximum of their children.
TEST(OctreeUpdate, ClearBox) {
  Octree tree = scanned_tree(0.04);
  const Octree before = tree;
  const Vec3 lo(0.5, -0.1, -0.3), hi(1.3, 0.6, 0.2);
  tree.clear_box(lo, hi);
  const OctreeKey klo = *tree.grid().key(lo), khi = *tree.grid().key(hi);
  // Every voxel of the scanned cube, not a sample (a sample's counts hung on the draws of the
  // generator the tests share).
  int kept = 0, cleared = 0;
  for (int i = 0; i < 81 * 81 * 81; ++i) {
    const OctreeKey k{{static_cast<std::uint16_t>(32768 - 40 + i % 81), static_cast<std::uint16_t>(32768 - 40 + i / 81 % 81),
                       static_cast<std::uint16_t>(32768 - 40 + i / (81 * 81))}};
    bool in = true;
    for (int a = 0; a < 3; ++a) in = in && k.k[a] >= klo.k[a] && k.k[a] <= khi.k[a];
    const auto now = tree.find(k), then = before.find(k);
    if (in) {
      EXPECT_FALSE(now.has_value());
      cleared += then.has_value();
    } else {
      ASSERT_EQ(now.has_value(), then.has_value());
      if (now) {
        EXPECT_EQ(now->log_odds, then->log_odds);
      }
      kept += now.has_value();
    }
  }
  EXPECT_GT(cleared, 100);
  EXPECT_GT(kept, 100);
  EXPECT_LT(tree.leaves().size(), before.leaves().size());
  EXPECT_LE(tree.node_count(), before.node_count());
  tree.clear_box(Vec3::Constant(-1e9), Vec3::Constant(1e9));
  EXPECT_TRUE(tree.empty());
  EXPECT_EQ(tree.node_count(), 0u);
}

}  // namespace
}  // namespace bvh_collision
