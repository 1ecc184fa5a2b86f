// OctreeDistanceField (octree/distance_field.h) against brute force over the tree's occupied
// cubes: its bound never exceeds the true distance from a point to every occupied cube (random
// points, points on voxel faces and corners, next to pruned blocks), it is the exact transform's
// (the squared centre distance to the nearest occupied voxel, found by brute force), it is never
// more than 2 sqrt(3) voxels loose under the cap, and it says nothing (0) outside its box.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/octree/distance_field.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

OctreeKey key_at(int x, int y, int z) {
  return OctreeKey{{std::uint16_t(x + kOctreeKeyOffset), std::uint16_t(y + kOctreeKeyOffset), std::uint16_t(z + kOctreeKeyOffset)}};
}

// Random occupied voxels in [-12, 12)^3, an 8^3 block at [0, 8)^3 (pruned into one leaf), free
// voxels around, and a cleared corner.
Octree scene(std::uint64_t seed) {
  Octree tree(0.05);
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> u(-12, 11);
  for (int i = 0; i < 150; ++i) tree.update(key_at(u(rng), u(rng), u(rng)), true);
  for (int i = 0; i < 150; ++i) tree.update(key_at(u(rng), u(rng), u(rng)), false);
  for (int x = 0; x < 8; ++x) {
    for (int y = 0; y < 8; ++y) {
      for (int z = 0; z < 8; ++z) tree.update(key_at(x, y, z), true);
    }
  }
  tree.clear_box(Vec3(-0.6, -0.6, -0.6), Vec3(-0.3, -0.3, -0.3));
  return tree;
}

double distance_to_cube(const Vec3& p, const Vec3& lo, double side) {
  double s = 0.0;
  for (int a = 0; a < 3; ++a) {
    const double d = std::max({lo[a] - p[a], 0.0, p[a] - (lo[a] + side)});
    s += d * d;
  }
  return std::sqrt(s);
}

struct Truth {
  double distance;          // from p to the nearest occupied cube
  std::int64_t centres = 0;  // smallest squared centre distance, in voxels, to an occupied voxel
};

Truth brute_force(const Octree& tree, const Vec3& p) {
  const double res = tree.resolution();
  const std::int64_t c[3] = {std::int64_t(std::floor(p.x() / res)), std::int64_t(std::floor(p.y() / res)),
                             std::int64_t(std::floor(p.z() / res))};
  Truth t{std::numeric_limits<double>::infinity(), std::numeric_limits<std::int64_t>::max()};
  for (const Octree::Leaf& leaf : tree.leaves()) {
    if (!tree.occupied(leaf.log_odds)) continue;
    t.distance = std::min(t.distance, distance_to_cube(p, tree.cube_min(leaf.key), tree.cube_size(leaf.depth)));
    const int side = 1 << (kOctreeDepth - leaf.depth);
    for (int x = 0; x < side; ++x) {
      for (int y = 0; y < side; ++y) {
        for (int z = 0; z < side; ++z) {
          const std::int64_t d[3] = {leaf.key.k[0] - kOctreeKeyOffset + x - c[0], leaf.key.k[1] - kOctreeKeyOffset + y - c[1],
                                     leaf.key.k[2] - kOctreeKeyOffset + z - c[2]};
          t.centres = std::min(t.centres, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        }
      }
    }
  }
  return t;
}

TEST(OctreeDistanceField, BoundsEqualTheExactTransformAndNeverExceedTheDistance) {
  for (const std::uint64_t seed : {1u, 2u, 3u}) {
    const Octree tree = scene(seed);
    const double res = tree.resolution(), cap = 0.3;
    const Vec3 lo(-0.5, -0.45, -0.5), hi(0.5, 0.55, 0.45);
    const OctreeDistanceField field = OctreeDistanceField::build(tree, lo, hi, cap);
    std::mt19937_64 rng(seed + 10);
    std::uniform_real_distribution<double> x(lo.x(), hi.x()), y(lo.y(), hi.y()), z(lo.z(), hi.z());
    std::uniform_int_distribution<int> face(-9, 9);
    int positive = 0;
    for (int i = 0; i < test::sized(3000); ++i) {
      Vec3 p(x(rng), y(rng), z(rng));
      if (i % 3 == 1) p.x() = face(rng) * res;                       // on a voxel face
      if (i % 3 == 2) p = Vec3(face(rng), face(rng), face(rng)) * res;  // on a voxel corner
      const Truth t = brute_force(tree, p);
      const double bound = field.lower_bound(p);
      ASSERT_LE(bound, t.distance) << "p = " << p.transpose() << ", seed " << seed;
      ASSERT_LE(bound, cap);
      // The exact transform: a point on a face may sit in either voxel, so only points inside one.
      const bool inside = i % 3 == 0;
      if (inside) {
        const double expected = std::max(
            0.0, std::min((std::sqrt(double(t.centres)) - std::sqrt(3.0)) * res, cap) - kVolumeMargin * (1.0 + p.lpNorm<Eigen::Infinity>() + cap));
        ASSERT_NEAR(bound, expected, 1e-12) << "p = " << p.transpose();
      }
      if (t.distance < cap) {
        ASSERT_GE(bound, t.distance - 2.0 * std::sqrt(3.0) * res - 1e-9) << "p = " << p.transpose();
      }
      positive += bound > 0.0;
    }
    EXPECT_GT(positive, test::sized(3000) / 10);  // the field says something useful
  }
}

TEST(OctreeDistanceField, OutsideItsBoxItKnowsNothingAndEmptyTreesAreFarEverywhere) {
  const Octree tree = scene(4);
  const OctreeDistanceField field = OctreeDistanceField::build(tree, Vec3(-0.2, -0.2, -0.2), Vec3(0.2, 0.2, 0.2), 0.25);
  EXPECT_EQ(field.lower_bound(Vec3(0.5, 0.0, 0.0)), 0.0);
  EXPECT_EQ(field.lower_bound(Vec3(0.0, -0.31, 0.0)), 0.0);
  EXPECT_EQ(field.lower_bound(Vec3(std::nan(""), 0.0, 0.0)), 0.0);
  EXPECT_EQ(field.lower_bound(Vec3(0.0, 0.0, std::numeric_limits<double>::infinity())), 0.0);
  EXPECT_EQ(field.lower_bound(Vec3(0.1, 0.1, 0.1)), 0.0);  // inside the pruned block

  const Octree empty(0.05);
  const OctreeDistanceField far = OctreeDistanceField::build(empty, Vec3(-0.2, -0.2, -0.2), Vec3(0.2, 0.2, 0.2), 0.25);
  EXPECT_NEAR(far.lower_bound(Vec3(0.01, 0.02, 0.03)), 0.25, 1e-9);
  EXPECT_EQ(OctreeDistanceField().lower_bound(Vec3::Zero()), 0.0);

  EXPECT_THROW(OctreeDistanceField::build(tree, Vec3::Zero(), Vec3(-1, 0, 0), 0.1), std::invalid_argument);
  EXPECT_THROW(OctreeDistanceField::build(tree, Vec3::Zero(), Vec3::Ones(), 0.0), std::invalid_argument);
  EXPECT_THROW(OctreeDistanceField::build(tree, Vec3::Zero(), Vec3(std::nan(""), 1, 1), 0.1), std::invalid_argument);
  EXPECT_THROW(OctreeDistanceField::build(tree, Vec3::Zero(), Vec3::Constant(100.0), 0.1), std::invalid_argument);
}

}  // namespace
}  // namespace bvh_collision
