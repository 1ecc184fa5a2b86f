// Rays with no return (octree/scan.h), one binary with test_octree.cpp: the pinhole model fitted
// to a depth image's cloud, the rays of its NaN pixels and what they clear, against a brute-force
// walk of each ray; rays clipped to the workspace instead of dropped.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <future>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/octree/octree.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/octree/voxel_set.h"
#include "octree_fixtures.h"

namespace bvh_collision {
namespace {

// ---- Rays with no return (octree/scan.h): the pinhole model fitted to a depth image's cloud, the
// rays of its NaN pixels, and what they clear, against a brute-force walk of each ray; rays clipped
// to the workspace instead of dropped, and the same tree as OctoMap's rule wherever both insert.
namespace no_return {

constexpr float kNan = std::numeric_limits<float>::quiet_NaN();
const PinholeCamera kCamera{300.0, 310.0, 31.5, 24.2};
constexpr std::size_t kWidth = 64, kHeight = 48;

// A depth image's cloud in the optical frame: a wall 2 m away behind a box 1.2 m away; pixels in
// `dark` (column range) return nothing, as a black or absent surface does.
std::vector<ScanPoint> depth_image(std::size_t dark_from, std::size_t dark_to) {
  std::vector<ScanPoint> cloud;
  for (std::size_t v = 0; v < kHeight; ++v) {
    for (std::size_t u = 0; u < kWidth; ++u) {
      if (u >= dark_from && u < dark_to) {
        cloud.emplace_back(kNan, kNan, kNan);
        continue;
      }
      const double z = (u > 20 && u < 40 && v > 10 && v < 30) ? 1.2 : 2.0;
      cloud.push_back(Vec3((u - kCamera.cx) / kCamera.fx * z, (v - kCamera.cy) / kCamera.fy * z, z).cast<float>());
    }
  }
  return cloud;
}

TEST(NoReturn, FitsTheCameraOfADepthImage) {
  const auto fitted = fit_pinhole(depth_image(50, 60), kWidth, kHeight);
  ASSERT_TRUE(fitted.has_value());
  EXPECT_NEAR(fitted->fx, kCamera.fx, 1e-3);
  EXPECT_NEAR(fitted->fy, kCamera.fy, 1e-3);
  EXPECT_NEAR(fitted->cx, kCamera.cx, 1e-4);
  EXPECT_NEAR(fitted->cy, kCamera.cy, 1e-4);
  // Not a pinhole camera's cloud: a spinning LiDAR's rings (azimuth by column, elevation by row).
  std::vector<ScanPoint> rings;
  for (std::size_t v = 0; v < 16; ++v) {
    for (std::size_t u = 0; u < 90; ++u) {
      const double azimuth = 0.02 * u - 0.9, elevation = 0.03 * v - 0.24;
      rings.push_back((5.0 * Vec3(std::sin(azimuth) * std::cos(elevation), std::sin(elevation), std::cos(azimuth) * std::cos(elevation))).cast<float>());
    }
  }
  EXPECT_FALSE(fit_pinhole(rings, 90, 16).has_value());
  // Too little to fit: one valid column; and a size that is not width x height.
  std::vector<ScanPoint> one_column(kWidth * kHeight, ScanPoint(kNan, kNan, kNan));
  for (std::size_t v = 0; v < kHeight; ++v) one_column[v * kWidth + 3] = ScanPoint(0.1f, 0.01f * v, 1.0f);
  EXPECT_FALSE(fit_pinhole(one_column, kWidth, kHeight).has_value());
  EXPECT_FALSE(fit_pinhole(depth_image(0, 0), kWidth, kHeight + 1).has_value());
}

// A camera model given by configuration is used for a cloud only if the cloud's points agree.
TEST(NoReturn, ACameraAgreesOnlyWithItsOwnClouds) {
  const std::vector<ScanPoint> cloud = depth_image(50, 60);
  EXPECT_TRUE(pinhole_agrees(cloud, kWidth, kHeight, kCamera));
  PinholeCamera wider = kCamera;
  wider.fx *= 0.95;
  EXPECT_FALSE(pinhole_agrees(cloud, kWidth, kHeight, wider)) << "a focal length 5 % off";
  PinholeCamera shifted = kCamera;
  shifted.cy += 2.0;
  EXPECT_FALSE(pinhole_agrees(cloud, kWidth, kHeight, shifted)) << "a centre 2 px off";
  EXPECT_FALSE(pinhole_agrees(cloud, kWidth, kHeight + 1, kCamera)) << "another size";
  EXPECT_FALSE(pinhole_agrees(cloud, kWidth, kHeight, PinholeCamera{})) << "not a camera";
  // Nothing returned: nothing contradicts it. A driver's zero points are no return either; a
  // point behind the camera is not a pinhole camera's.
  std::vector<ScanPoint> dark(kWidth * kHeight, ScanPoint(kNan, kNan, kNan));
  EXPECT_TRUE(pinhole_agrees(dark, kWidth, kHeight, wider));
  std::vector<ScanPoint> zeros = cloud;
  zeros[5] = ScanPoint::Zero();
  EXPECT_TRUE(pinhole_agrees(zeros, kWidth, kHeight, kCamera));
  std::vector<ScanPoint> behind = cloud;
  behind[5] = -behind[5];
  EXPECT_FALSE(pinhole_agrees(behind, kWidth, kHeight, kCamera));
}

TEST(NoReturn, EachDarkPixelGivesItsRayToTheRange) {
  const std::vector<ScanPoint> cloud = depth_image(50, 60);
  const std::vector<ScanPoint> ends = no_return_ends(cloud, kWidth, kHeight, kCamera, 3.0);
  ASSERT_EQ(ends.size(), 10 * kHeight);
  std::size_t k = 0;
  for (std::size_t v = 0; v < kHeight; ++v) {
    for (std::size_t u = 50; u < 60; ++u, ++k) {
      const Vec3 e = ends[k].cast<double>();
      EXPECT_NEAR(e.norm(), 3.0, 1e-5);
      // Projected back through the camera, the end lands on its pixel.
      EXPECT_NEAR(kCamera.fx * e.x() / e.z() + kCamera.cx, double(u), 1e-4);
      EXPECT_NEAR(kCamera.fy * e.y() / e.z() + kCamera.cy, double(v), 1e-4);
    }
  }
  EXPECT_THROW(no_return_ends(cloud, kWidth, kHeight + 1, kCamera, 3.0), std::invalid_argument);
  EXPECT_THROW(no_return_ends(cloud, kWidth, kHeight, PinholeCamera{}, 3.0), std::invalid_argument);
  EXPECT_THROW(no_return_ends(cloud, kWidth, kHeight, kCamera, std::nan("")), std::invalid_argument);
  EXPECT_THROW(no_return_ends(cloud, kWidth, kHeight, kCamera, 0.0), std::invalid_argument);
}

using KeySet = std::set<std::array<std::uint16_t, 3>>;

// Every voxel the tree holds (pruned leaves expanded), by key.
KeySet observed(const Octree& tree) {
  KeySet out;
  for (const Octree::Leaf& l : tree.leaves()) {
    const int side = 1 << (kOctreeDepth - l.depth);
    for (int x = 0; x < side; ++x) {
      for (int y = 0; y < side; ++y) {
        for (int z = 0; z < side; ++z) {
          out.insert({std::uint16_t(l.key.k[0] + x), std::uint16_t(l.key.k[1] + y), std::uint16_t(l.key.k[2] + z)});
        }
      }
    }
  }
  return out;
}

// How long a piece of the segment a-b lies in the voxel's cube (slabs).
double chord_in_cube(const OctreeGrid& grid, const std::array<std::uint16_t, 3>& key, const Vec3& a, const Vec3& b) {
  const double h = grid.resolution() / 2;
  const Vec3 c(grid.center(key[0]), grid.center(key[1]), grid.center(key[2])), d = b - a;
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-15) {
      if (std::abs(a[i] - c[i]) > h) return 0.0;
      continue;
    }
    const double t1 = (c[i] - h - a[i]) / d[i], t2 = (c[i] + h - a[i]) / d[i];
    lo = std::max(lo, std::min(t1, t2));
    hi = std::min(hi, std::max(t1, t2));
  }
  return std::max(0.0, hi - lo) * d.norm();
}

// The brute-force walk: the voxels a ray's points fall in, stepped at a hundredth of a voxel,
// within the workspace (OctoMap's bounding box: the keys from its min corner's to its max corner's),
// without the end's voxel.
void walk(const OctreeGrid& grid, const Vec3& a, const Vec3& b, const ScanWorkspace& box, KeySet& out) {
  const auto end = grid.key(b);
  const int steps = static_cast<int>(std::ceil((b - a).norm() / (grid.resolution() * 1e-2)));
  for (int i = 0; i <= steps; ++i) {
    const Vec3 p = a + (b - a) * (double(i) / steps);
    const auto k = grid.key(p);
    if (!k || (end && *k == *end)) continue;
    const OctreeKey lo = *grid.key(box.min.cast<double>()), hi = *grid.key(box.max.cast<double>());
    bool inside = true;
    for (int a = 0; a < 3; ++a) inside = inside && k->k[a] >= lo.k[a] && k->k[a] <= hi.k[a];
    if (!inside) continue;
    out.insert({k->k[0], k->k[1], k->k[2]});
  }
}

// The camera placed in the world, its dark pixels' rays inserted with a workspace that cuts them:
// the voxels freed are the brute-force walk's, but for voxels a ray only grazes (its piece in the
// cube shorter than the walk's step, which the walk may step over).
TEST(NoReturn, RaysClearWhatABruteForceWalkCrosses) {
  const Vec3 origin(0.31, -0.27, 0.52);
  // The optical frame (z forward, y down) looking along world x, turned a little.
  Eigen::Matrix3d optical;
  optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.4, Vec3(0.2, 1.0, 0.3).normalized()).toRotationMatrix() * optical;
  std::vector<ScanPoint> ends = no_return_ends(depth_image(45, 64), kWidth, kHeight, kCamera, 1.5);
  for (ScanPoint& e : ends) e = (R * e.cast<double>() + origin).cast<float>();
  Octree tree(0.02);
  ScanOptions options;
  options.max_range = 1.5;
  options.workspace = ScanWorkspace{ScanPoint(-0.5f, -1.0f, -0.2f), ScanPoint(1.2f, 0.6f, 1.0f)};
  options.clip_rays_to_workspace = true;
  const ScanStats stats = insert_scan(tree, {}, ends, origin.cast<float>(), options);
  EXPECT_EQ(stats.occupied, 0u);
  EXPECT_EQ(stats.skipped_workspace, 0u) << "clipped, not dropped";
  KeySet brute;
  for (const ScanPoint& e : ends) walk(tree.grid(), origin.cast<float>().cast<double>(), e.cast<double>(), *options.workspace, brute);
  const KeySet got = observed(tree);
  ASSERT_GT(brute.size(), 500u);
  // Each freed voxel once, as a miss.
  for (const Octree::Leaf& l : tree.leaves()) {
    EXPECT_FLOAT_EQ(l.log_odds, tree.model().miss);
  }
  // The longest piece of any ray in the voxel's cube.
  auto chord = [&](const std::array<std::uint16_t, 3>& key) {
    double longest = 0.0;
    for (const ScanPoint& e : ends) longest = std::max(longest, chord_in_cube(tree.grid(), key, origin.cast<float>().cast<double>(), e.cast<double>()));
    return longest;
  };
  const double step = tree.resolution() * 1e-2;
  std::size_t only_walked = 0, only_freed = 0, grazed = 0;
  for (const auto& k : brute) only_walked += !got.count(k) && chord(k) > 1e-9;
  for (const auto& k : got) {
    if (brute.count(k)) continue;
    const double c = chord(k);
    only_freed += c >= step;
    grazed += c < step;
  }
  EXPECT_LT(grazed, brute.size() / 100) << "voxels freed that the walk stepped over";
  EXPECT_EQ(only_walked, 0u) << "voxels the walk crosses that were not freed";
  EXPECT_EQ(only_freed, 0u) << "voxels freed that no ray passes through";
}

// A wall past the workspace: OctoMap's rule drops its rays, so a stale voxel in front of it stays;
// clipped, its rays clear it. Where every end lies in the box and within range, both rules build
// the same tree.
TEST(NoReturn, ClippedRaysClearInFrontOfAFarWallAndChangeNothingElse) {
  const ScanPoint origin(0.0f, 0.0f, 0.5f);
  std::vector<ScanPoint> wall;
  for (float y = -0.3f; y <= 0.3f; y += 0.01f) {
    for (float z = 0.2f; z <= 0.8f; z += 0.01f) wall.emplace_back(3.0f, y, z);
  }
  ScanOptions options;
  options.max_range = 5.0;
  options.workspace = ScanWorkspace{ScanPoint(-1, -1, 0), ScanPoint(1.5f, 1, 1)};
  const ScanPoint stale(1.0f, 0.0f, 0.5f);
  for (const bool clip : {false, true}) {
    Octree tree(0.05);
    insert_points(tree, {stale});
    options.clip_rays_to_workspace = clip;
    for (int i = 0; i < 5; ++i) insert_scan(tree, wall, origin, options);
    const auto found = tree.find(*tree.grid().key(stale.cast<double>()));
    ASSERT_TRUE(found.has_value());
    EXPECT_EQ(tree.occupied(found->log_odds), !clip) << (clip ? "clipped" : "OctoMap's rule");
  }
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> x(-0.9f, 1.4f), y(-0.9f, 0.9f), z(0.05f, 0.95f);
  std::vector<ScanPoint> inside;
  for (int i = 0; i < 20000; ++i) inside.emplace_back(x(rng), y(rng), z(rng));
  Octree a(0.05), b(0.05);
  options.clip_rays_to_workspace = false;
  insert_scan(a, inside, origin, options);
  options.clip_rays_to_workspace = true;
  insert_scan(b, inside, origin, options);
  const auto la = a.leaves(), lb = b.leaves();
  ASSERT_EQ(la.size(), lb.size());
  for (std::size_t i = 0; i < la.size(); ++i) {
    EXPECT_TRUE(la[i].key == lb[i].key && la[i].depth == lb[i].depth && la[i].log_odds == lb[i].log_odds) << i;
  }
}

}  // namespace no_return

}  // namespace
}  // namespace bvh_collision
