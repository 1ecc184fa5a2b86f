// The ray walk every scan's rays take (octree/detail/ray_walk.h), each build of it against
// OctoMap's computeRayKeys ray for ray (one binary with test_octree.cpp).
#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvh_collision/octree/octree.h"
#include "bvh_collision/octree/scan.h"
#include "octree_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

using test::random_scan;
using test::rng;
using test::walks;

// ray_keys, the walk every scan's rays take, against OctoMap's computeRayKeys ray for ray: the
// same voxels in the same order. Rays of every kind the step's choice of axis meets: random,
// along an axis or a plane (crossings at infinity), through voxel corners (ties between axes),
// ends on voxel planes, long rays, rays by the ends of the 16-bit key range, and rays inside one
// voxel.
TEST(OctreeAgainstOctomap, EveryRayCrossesOctomapsVoxelsInItsOrder) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::uniform_int_distribution<int> cell(-40, 40), kind(0, 6);
  int compared = 0, long_walks = 0;
  // Per resolution; a twentieth under the sanitizers, where a quarter took 24 s (all of them take
  // 1-3 s in the Release pass).
  const int rays = test::sanitized() ? 1000 : 20000;
  for (const double res : {0.01, 0.05, 0.2}) {
    const OctreeGrid grid(res);
    octomap::OcTree reference(res);
    const float r = static_cast<float>(res), edge = static_cast<float>(res * (kOctreeKeyOffset - 3));
    for (int i = 0; i < rays; ++i) {
      ScanPoint a(u(rng()), u(rng()), u(rng())), b(u(rng()), u(rng()), u(rng()));
      switch (kind(rng())) {
        case 1: b = a, b[i % 3] += 3.0f * u(rng()); break;                  // along an axis
        case 2: b = a + ScanPoint(u(rng()), u(rng()), u(rng())), b[i % 3] = a[i % 3]; break;  // in a plane
        case 3:  // from voxel corner to voxel corner: crossings tie
          a = r * ScanPoint(float(cell(rng())), float(cell(rng())), float(cell(rng())));
          b = a + r * float(cell(rng())) * ScanPoint(1.0f, (i & 1) ? 1.0f : -1.0f, (i & 2) ? 1.0f : 2.0f);
          break;
        case 4: b = r * ScanPoint(float(cell(rng())), float(cell(rng())), float(cell(rng()))); break;  // end on voxel planes
        case 5: b = a + 60.0f * ScanPoint(u(rng()), u(rng()), u(rng())); break;  // long
        case 6:  // by the key range's ends (OctoMap's keys wrap past them, as ours)
          a = ScanPoint(edge * (i & 1 ? 1.0f : -1.0f), edge * u(rng()), 0.5f * edge * u(rng()));
          b = a + ScanPoint(5.0f * r * u(rng()), u(rng()), u(rng()));
          break;
        default: break;
      }
      if (i % 97 == 0) b = a + ScanPoint(0.1f * r, 0.0f, 0.0f);  // within a voxel or just across
      octomap::KeyRay ray;
      const bool theirs_ok = reference.computeRayKeys(octomap::point3d(a.x(), a.y(), a.z()), octomap::point3d(b.x(), b.y(), b.z()), ray);
      for (const SimdPath walk : walks()) {
        std::vector<OctreeKey> ours_keys;
        const bool ours_ok = ray_keys(grid, a, b, ours_keys, walk);
        ASSERT_EQ(ours_ok, theirs_ok) << res << " ray " << i << " walk " << int(walk);
        ASSERT_EQ(ours_keys.size(), ray.size()) << res << " ray " << i << " walk " << int(walk);
        std::size_t k = 0;
        for (auto it = ray.begin(); it != ray.end(); ++it, ++k) {
          ASSERT_TRUE(ours_keys[k].k[0] == (*it)[0] && ours_keys[k].k[1] == (*it)[1] && ours_keys[k].k[2] == (*it)[2])
              << res << " ray " << i << " voxel " << k << " walk " << int(walk);
        }
        ++compared;
      }
      long_walks += ray.size() > 100;
    }
  }
  EXPECT_EQ(compared, 3 * rays * static_cast<int>(walks().size()));
  EXPECT_GT(long_walks, rays / 20);
}

// The default is the CPU's best build; one it lacks is refused before the tree changes.
TEST(OctreeAgainstOctomap, TheWalkIsTheCpusBestAndAnAbsentOneIsRefused) {
  EXPECT_EQ(resolve_simd_path(SimdPath::kAuto, "walk"), avx2_available() ? SimdPath::kAvx2 : SimdPath::kGeneric);
  Octree tree(0.05);
  const std::vector<ScanPoint> scan = random_scan(ScanPoint(0, 0, 1), 200, 1.5);
  ScanOptions avx2;
  avx2.simd = SimdPath::kAvx2;
  if (avx2_available()) {
    EXPECT_GT(insert_scan(tree, scan, ScanPoint(0, 0, 1), avx2).free, 0u);
  } else {
    try {
      insert_scan(tree, scan, ScanPoint(0, 0, 1), avx2);
      ADD_FAILURE() << "the AVX2 walk ran on a CPU without AVX2";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("ScanOptions::simd"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(tree.leaves().empty());
  }
}

}  // namespace
}  // namespace bvh_collision
