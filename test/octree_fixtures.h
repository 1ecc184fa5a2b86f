// What the octree tests share (test_octree.cpp, test_octree_queries.cpp): a seeded generator,
// the leaves of our tree and of OctoMap's as comparable maps, and a depth-camera-like scan.
#pragma once

#include <octomap/OcTree.h>

#include <map>
#include <random>
#include <tuple>
#include <vector>

#include "bvh_collision/octree/octree.h"
#include "bvh_collision/octree/scan.h"

namespace bvh_collision::test {

inline std::mt19937_64& rng() {
  static std::mt19937_64 r(5);
  return r;
}

using LeafMap = std::map<std::tuple<int, int, int, int>, float>;  // (x, y, z, depth) -> log-odds

inline LeafMap ours(const Octree& tree) {
  LeafMap m;
  for (const Octree::Leaf& l : tree.leaves()) m[{l.key.k[0], l.key.k[1], l.key.k[2], l.depth}] = l.log_odds;
  return m;
}

inline LeafMap theirs(const octomap::OcTree& tree) {
  LeafMap m;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    // OctoMap's leaf key is its centre key at depth; the lowest corner voxel is what we report.
    const int depth = static_cast<int>(it.getDepth());
    const int shift = kOctreeDepth - depth;
    const octomap::OcTreeKey k = it.getKey();
    auto corner = [&](int v) { return (v >> shift) << shift; };
    m[{corner(k[0]), corner(k[1]), corner(k[2]), depth}] = it->getLogOdds();
  }
  return m;
}

// A depth-camera-like scan: rays from `origin` in a cone, ending on a plane and a box, some
// beyond `far`.
// The ray walk's builds this CPU runs (ScanOptions::simd): each must give OctoMap's tree.
inline std::vector<SimdPath> walks() {
  if (avx2_available()) return {SimdPath::kGeneric, SimdPath::kAvx2};
  return {SimdPath::kGeneric};
}

inline std::vector<ScanPoint> random_scan(const ScanPoint& origin, int n, double far) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f), r(0.2f, static_cast<float>(far) * 1.3f);
  std::vector<ScanPoint> p;
  for (int i = 0; i < n; ++i) {
    ScanPoint d(u(rng()), u(rng()), u(rng()) * 0.5f - 0.6f);
    d.normalize();
    p.push_back(origin + d * r(rng()));
  }
  return p;
}

}  // namespace bvh_collision::test
