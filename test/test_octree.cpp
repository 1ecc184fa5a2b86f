// The environment octree against OctoMap itself: the same scans inserted into both give the same
// leaves (key, depth, log-odds) bit for bit; and the seed's index scheme against a direct
// computation from coordinates (rays with no return: test_octree_no_return.cpp, one binary).
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
#include "robot_data.h"

namespace bvh_collision {
namespace {

using test::LeafMap;
using test::ours;
using test::random_scan;
using test::rng;
using test::sized;
using test::theirs;
using test::walks;

// The same scans into OctoMap and into one tree per build of the walk (walks()).
void expect_same_as_octomap(double resolution, const ScanOptions& options, int scans, int all_points) {
  const int points = sized(all_points);  // (a quarter under the sanitizers)
  const double max_range = options.max_range;
  SCOPED_TRACE("resolution " + std::to_string(resolution) + " max_range " + std::to_string(max_range) +
               (options.workspace ? " workspace" : "") + " threads " + std::to_string(options.threads));
  std::vector<Octree> trees(walks().size(), Octree(resolution));
  octomap::OcTree reference(resolution);
  if (options.workspace) {
    octomap::point3d lo(options.workspace->min.x(), options.workspace->min.y(), options.workspace->min.z());
    octomap::point3d hi(options.workspace->max.x(), options.workspace->max.y(), options.workspace->max.z());
    reference.setBBXMin(lo);
    reference.setBBXMax(hi);
    reference.useBBXLimit(true);
  }
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int s = 0; s < scans; ++s) {
    const ScanPoint origin(u(rng()), u(rng()), 1.0f + u(rng()) * 0.5f);
    const auto scan = random_scan(origin, points, max_range > 0 ? max_range : 2.0);
    octomap::Pointcloud cloud;
    for (const ScanPoint& p : scan) cloud.push_back(p.x(), p.y(), p.z());
    reference.insertPointCloud(cloud, octomap::point3d(origin.x(), origin.y(), origin.z()), max_range);
    const LeafMap b = theirs(reference);
    for (std::size_t w = 0; w < trees.size(); ++w) {
      SCOPED_TRACE(walks()[w] == SimdPath::kAvx2 ? "AVX2 walk" : "default walk");
      Octree& tree = trees[w];
      ScanOptions walk = options;
      walk.simd = walks()[w];
      insert_scan(tree, scan, origin, walk);
      const LeafMap a = ours(tree);
      ASSERT_EQ(a.size(), b.size()) << "after scan " << s;
      int different = 0;
      for (const auto& [key, value] : b) {
        const auto it = a.find(key);
        different += it == a.end() || it->second != value;
      }
      ASSERT_EQ(different, 0) << "after scan " << s;
      EXPECT_EQ(tree.node_count(), reference.size());
      // Not a trivial agreement: occupied and free voxels, and pruned nodes above voxel depth.
      int occupied = 0, pruned = 0;
      for (const Octree::Leaf& l : tree.leaves()) {
        occupied += tree.occupied(l.log_odds);
        pruned += l.depth < kOctreeDepth;
      }
      EXPECT_GT(occupied, points / 20);
      EXPECT_GT(a.size(), static_cast<std::size_t>(occupied));
      if (s == scans - 1) {
        EXPECT_GT(pruned, 0) << "no pruned node: the pruning rule was not exercised";
      }
    }
  }
}

ScanOptions with(double max_range, int threads = 1, SimdPath walk = SimdPath::kGeneric) {
  ScanOptions options;
  options.max_range = max_range;
  options.threads = threads;
  options.simd = walk;
  return options;
}

TEST(OctreeAgainstOctomap, OneScan) {
  for (const double res : {0.01, 0.05, 0.2}) expect_same_as_octomap(res, with(-1.0), 1, 3000);
}

TEST(OctreeAgainstOctomap, ManyScansWithMaxRange) {
  for (const double res : {0.02, 0.1}) expect_same_as_octomap(res, with(1.5), 8, 2000);
}

// Rays cast on two threads and merged: the same tree.
TEST(OctreeAgainstOctomap, ThreadedScans) {
  expect_same_as_octomap(0.03, with(-1.0, 2), 3, 20000);
  expect_same_as_octomap(0.05, with(1.2, 2), 3, 20000);
}

// The workspace box is OctoMap's bounding-box limit, set on the reference tree.
TEST(OctreeAgainstOctomap, ScansInAWorkspace) {
  for (const double max_range : {-1.0, 1.5}) {
    ScanOptions options = with(max_range);
    options.workspace = ScanWorkspace{ScanPoint(-0.8f, -0.6f, -0.5f), ScanPoint(0.7f, 0.9f, 0.8f)};
    expect_same_as_octomap(0.04, options, 4, 3000);
  }
}

// Crossed voxels marked in a bitmap of the scan's box or in the hash set of blocks
// (ScanOptions::max_dense_voxels = 0), by either build of the walk: one tree, OctoMap's, in every way a scan is inserted
// (threads, max_range, a workspace, rays clipped to it with clear-only ones), with sensors inside
// and outside the workspace, end points on voxel planes at the edges of the box, and clouds
// whose box is too large for the bitmap (its cube about the sensor, which most rays leave).
TEST(OctreeAgainstOctomap, BitmapAndSetOfCrossedVoxelsGiveOneTree) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const ScanWorkspace box{ScanPoint(-0.8f, -0.6f, -0.5f), ScanPoint(0.7f, 0.9f, 0.8f)};
  int compared = 0;
  for (int mode = 0; mode < 10; ++mode) {
    const double res = mode % 2 ? 0.04 : 0.05;
    ScanOptions dense = with(mode & 2 ? 1.2 : -1.0, mode & 1 ? 2 : 1);
    if (mode >= 4 && mode < 8) dense.workspace = box;
    dense.clip_rays_to_workspace = mode >= 6 && mode < 8;
    // A bitmap of 9 x 9 x 9 voxels about the sensor: most rays leave it for the set.
    if (mode >= 8) dense.max_dense_voxels = 9 * 9 * 9;
    ScanOptions sparse = dense, best = dense;
    sparse.max_dense_voxels = 0;
    best.simd = walks().back();  // the AVX2 walk where the CPU has it
    Octree a(res), b(res), c(res);
    octomap::OcTree reference(res);
    if (dense.workspace && !dense.clip_rays_to_workspace) {
      octomap::point3d lo(box.min.x(), box.min.y(), box.min.z()), hi(box.max.x(), box.max.y(), box.max.z());
      reference.setBBXMin(lo);
      reference.setBBXMax(hi);
      reference.useBBXLimit(true);
    }
    for (int s = 0; s < 3; ++s) {
      // Outside the workspace on the last scan: its rays enter the box from outside.
      const ScanPoint origin = s == 2 ? ScanPoint(1.6f, 1.5f, 1.4f) : ScanPoint(0.3f * u(rng()), 0.3f * u(rng()), 0.2f);
      std::vector<ScanPoint> scan = random_scan(origin, sized(5000), 1.8), clearing = random_scan(origin, sized(500), 2.5);
      // Ends on voxel planes, the box's extremes among them.
      for (int k = -30; k <= 30; k += 3) scan.push_back(ScanPoint(float(res * k), float(res * (k % 7)), float(res * -30)));
      if (s == 1) scan.push_back(ScanPoint(250.0f, -3.0f, 1.0f));  // far: a box past the bitmap's limit
      const std::vector<ScanPoint> none;
      const std::vector<ScanPoint>& clear_only = dense.clip_rays_to_workspace ? clearing : none;
      // (The far point's box is too large for a bitmap of it: the cube about the sensor.)
      EXPECT_TRUE(insert_scan(a, scan, clear_only, origin, dense).bitmap) << "mode " << mode << " scan " << s;
      EXPECT_FALSE(insert_scan(b, scan, clear_only, origin, sparse).bitmap);
      EXPECT_TRUE(insert_scan(c, scan, clear_only, origin, best).bitmap);
      if (!dense.clip_rays_to_workspace) {
        octomap::Pointcloud cloud;
        for (const ScanPoint& p : scan) cloud.push_back(p.x(), p.y(), p.z());
        reference.insertPointCloud(cloud, octomap::point3d(origin.x(), origin.y(), origin.z()), dense.max_range);
      }
    }
    ASSERT_EQ(ours(a), ours(b)) << "mode " << mode;
    ASSERT_EQ(ours(a), ours(c)) << "mode " << mode;
    if (!dense.clip_rays_to_workspace) {
      ASSERT_EQ(ours(a), theirs(reference)) << "mode " << mode;
    }
    EXPECT_GT(a.leaves().size(), 1000u) << "mode " << mode;
    ++compared;
  }
  EXPECT_EQ(compared, 10);
}

TEST(OctreeKeys, SeedIndexFromCoordinates) {
  const OctreeGrid grid(0.05);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int i = 0; i < 2000; ++i) {
    // Half the points exactly on voxel boundaries (splitting planes of every level above).
    Vec3 p(u(rng()), u(rng()), u(rng()));
    if (i % 2) p = (p / 0.05).array().round() * 0.05;
    const auto key = grid.key(p);
    ASSERT_TRUE(key);
    std::uint64_t index = 0;
    for (int depth = 0; depth < kOctreeDepth; ++depth) {
      // The parent's centre at this depth, from coordinates: the cube of side
      // resolution * 2^(16 - depth) containing p, split in half.
      const double side = 0.05 * std::ldexp(1.0, kOctreeDepth - depth);
      int b = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const double scaled = std::floor(p[axis] * (1.0 / 0.05)) + kOctreeKeyOffset;  // OctoMap's rule
        const double lower = std::floor(scaled / (side / 0.05)) * (side / 0.05);
        const bool positive = scaled >= lower + side / 0.05 / 2;
        b |= positive << (2 - axis);
      }
      EXPECT_EQ(child_bits(*key, depth), b);
      const std::uint64_t child = child_index(index, b);
      EXPECT_EQ(parent_index(child), index);
      EXPECT_EQ(bits_of_index(child), b);
      index = child;
    }
    EXPECT_EQ(node_index(*key, kOctreeDepth), index);
  }
  // The seed's example: node 30's parent is 3 and b = 5 (x and z positive, y negative).
  EXPECT_EQ(parent_index(30), 3u);
  EXPECT_EQ(bits_of_index(30), 5);
}

TEST(OctreeKeys, PointsOnSplittingPlanesGoToThePositiveSide) {
  const OctreeGrid grid(0.25);  // exact in binary
  const auto on_plane = grid.key(Vec3(0.0, 0.5, -0.25));
  ASSERT_TRUE(on_plane);
  EXPECT_EQ(on_plane->k[0], kOctreeKeyOffset);      // 0 belongs to [0, 0.25)
  EXPECT_EQ(on_plane->k[1], kOctreeKeyOffset + 2);  // 0.5 to [0.5, 0.75)
  EXPECT_EQ(on_plane->k[2], kOctreeKeyOffset - 1);  // -0.25 to [-0.25, 0)
  EXPECT_EQ(child_bits(*on_plane, 0), 0b110);       // x, y on the root's positive side, z negative
}

// The voxel set against std::set: membership, union, difference, and the depth-first order
// against morton_code computed bit by bit.
TEST(VoxelSet, AgainstStdSet) {
  std::uniform_int_distribution<int> near(32700, 32830), any(0, 65535);
  VoxelSet a, b;
  std::set<OctreeKey> ra, rb;
  for (int i = 0; i < 20000; ++i) {
    const auto coord = [&](bool wide) { return static_cast<std::uint16_t>(wide ? any(rng()) : near(rng())); };
    const bool wide = i % 10 == 0;
    const OctreeKey k{{coord(wide), coord(wide), coord(wide)}};
    if (i % 3) {
      a.insert(k);
      ra.insert(k);
    } else {
      b.insert(k);
      rb.insert(k);
    }
  }
  EXPECT_EQ(a.size(), ra.size());
  for (const OctreeKey& k : rb) {
    EXPECT_EQ(a.contains(k), ra.count(k) == 1);
  }
  VoxelSet difference = a;
  difference.erase_all(b);
  a.insert_all(b);
  ra.insert(rb.begin(), rb.end());
  const std::vector<OctreeKey> all = a.sorted_keys();
  ASSERT_EQ(all.size(), ra.size());
  for (std::size_t i = 1; i < all.size(); ++i) {
    ASSERT_LT(morton_code(all[i - 1]), morton_code(all[i]));
    // Depth-first order: the first differing level decides, x bit above y above z.
    int d = 0;
    while (child_bits(all[i - 1], d) == child_bits(all[i], d)) ++d;
    ASSERT_LT(child_bits(all[i - 1], d), child_bits(all[i], d));
  }
  std::size_t only_a = 0;
  for (const OctreeKey& k : all) {
    const bool in_b = rb.count(k) == 1;
    only_a += !in_b;
    EXPECT_EQ(difference.contains(k), !in_b);
  }
  EXPECT_EQ(difference.size(), only_a);
}

// The bitmap of a box of keys against std::set: inserts inside and outside the box (refused),
// membership, union, and every key handed to a VoxelSet once, for boxes of odd sizes whose rows
// start and end inside words, one voxel wide, and at the ends of the key range.
TEST(VoxelBitGrid, AgainstStdSet) {
  const std::vector<std::pair<OctreeKey, OctreeKey>> boxes = {
      {OctreeKey{{32700, 32710, 32720}}, OctreeKey{{32730, 32722, 32790}}},
      {OctreeKey{{0, 0, 0}}, OctreeKey{{6, 70, 129}}},
      {OctreeKey{{65530, 100, 65400}}, OctreeKey{{65535, 100, 65535}}},
      {OctreeKey{{5, 5, 5}}, OctreeKey{{5, 5, 5}}}};
  for (const auto& [lo, hi] : boxes) {
    ASSERT_EQ(VoxelBitGrid::volume(lo, hi), std::uint64_t(hi.k[0] - lo.k[0] + 1) * (hi.k[1] - lo.k[1] + 1) * (hi.k[2] - lo.k[2] + 1));
    VoxelBitGrid a(lo, hi), b(lo, hi);
    std::set<OctreeKey> ra, rb;
    auto around = [&](int i) {
      std::uniform_int_distribution<int> d(std::max(0, lo.k[i] - 2), std::min(65535, hi.k[i] + 2));
      return static_cast<std::uint16_t>(d(rng()));
    };
    int refused = 0;
    for (int n = 0; n < 5000; ++n) {
      const OctreeKey k{{around(0), around(1), around(2)}};
      bool inside = true;
      for (int i = 0; i < 3; ++i) inside = inside && k.k[i] >= lo.k[i] && k.k[i] <= hi.k[i];
      VoxelBitGrid& grid = n % 3 ? a : b;
      ASSERT_EQ(grid.insert(k.k[0], k.k[1], k.k[2]), inside);
      refused += !inside;
      if (inside) (n % 3 ? ra : rb).insert(k);
    }
    EXPECT_GT(refused, 0);
    EXPECT_EQ(a.size(), ra.size());
    for (const OctreeKey& k : rb) {
      EXPECT_EQ(a.contains(k), ra.count(k) == 1);
    }
    a.insert_all(b);
    ra.insert(rb.begin(), rb.end());
    VoxelSet set;
    a.append_to(set);
    EXPECT_EQ(set.size(), ra.size());
    for (const OctreeKey& k : ra) {
      ASSERT_TRUE(set.contains(k) && a.contains(k));
    }
  }
}

// The one-descent batch update against one update per key (itself checked against OctoMap):
// random keys in a small region so that pruned nodes form, clamps are hit and pruned nodes are
// expanded again.
TEST(OctreeUpdate, SortedBatchEqualsOneByOne) {
  std::uniform_int_distribution<int> coord(32760, 32775);
  Octree batch(0.1), single(0.1);
  for (int round = 0; round < 30; ++round) {
    VoxelSet keys;
    for (int i = 0; i < 1500; ++i) {
      keys.insert(OctreeKey{{static_cast<std::uint16_t>(coord(rng())), static_cast<std::uint16_t>(coord(rng())),
                             static_cast<std::uint16_t>(coord(rng()))}});
    }
    // Eight siblings updated alike every round: a node pruned whatever the random keys (which
    // prune only by chance, depending on what earlier tests drew from the shared generator).
    for (int child = 0; child < 8; ++child) {
      keys.insert(OctreeKey{{static_cast<std::uint16_t>(32776 + (child & 1)), static_cast<std::uint16_t>(32776 + (child >> 1 & 1)),
                             static_cast<std::uint16_t>(32776 + (child >> 2))}});
    }
    const std::vector<OctreeKey> sorted = keys.sorted_keys();
    const bool hit = round % 3 != 0;
    batch.update_sorted(sorted, hit);
    for (const OctreeKey& k : sorted) single.update(k, hit);
    const auto a = batch.leaves(), b = single.leaves();
    ASSERT_EQ(a.size(), b.size()) << "round " << round;
    for (std::size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a[i].key, b[i].key);
      ASSERT_EQ(a[i].depth, b[i].depth);
      ASSERT_EQ(a[i].log_odds, b[i].log_odds);
    }
    ASSERT_EQ(batch.node_count(), single.node_count());
  }
  int pruned = 0;
  for (const auto& l : batch.leaves()) pruned += l.depth < kOctreeDepth;
  EXPECT_GT(pruned, 0);
}

// End points without rays: each voxel once as occupied, as octomap's updateNode per distinct voxel.
TEST(OctreeAgainstOctomap, OccupiedOnlyInsert) {
  Octree tree(0.05);
  octomap::OcTree reference(0.05);
  for (int s = 0; s < 3; ++s) {
    const auto scan = random_scan(ScanPoint(0, 0, 1), 4000, 2.0);
    std::set<OctreeKey> seen;
    for (const ScanPoint& p : scan) {
      const auto k = tree.grid().key(Vec3(p.cast<double>()));
      if (k && seen.insert(*k).second) reference.updateNode(octomap::OcTreeKey(k->k[0], k->k[1], k->k[2]), true);
    }
    const ScanStats stats = insert_points(tree, scan);
    EXPECT_EQ(stats.occupied, seen.size());
  }
  EXPECT_EQ(ours(tree), theirs(reference));
}

// Rays that only clear (the self filter's robot points and shadows): OctoMap's own ray keys for
// them join the scan's free set, their end voxels are not marked, and the update is applied as
// insertPointCloud applies one (free first, each voxel once, an occupied end never also freed).
TEST(OctreeAgainstOctomap, ClearOnlyRays) {
  for (const int threads : {1, 2}) {
    Octree tree(0.05);
    octomap::OcTree reference(0.05);
    for (int s = 0; s < 3; ++s) {
      const ScanPoint origin(0.2f * s, 0.1f, 1.2f);
      const auto marked = random_scan(origin, 6000, 1.5), clearing = random_scan(origin, 6000, 1.0);
      octomap::Pointcloud cloud;
      for (const ScanPoint& p : marked) cloud.push_back(p.x(), p.y(), p.z());
      const octomap::point3d o(origin.x(), origin.y(), origin.z());
      octomap::KeySet free, occupied;
      reference.computeUpdate(cloud, o, free, occupied, -1.0);
      octomap::KeyRay ray;
      for (const ScanPoint& p : clearing) {
        ASSERT_TRUE(reference.computeRayKeys(o, octomap::point3d(p.x(), p.y(), p.z()), ray));
        free.insert(ray.begin(), ray.end());
      }
      for (const auto& k : occupied) free.erase(k);
      for (const auto& k : free) reference.updateNode(k, false);
      for (const auto& k : occupied) reference.updateNode(k, true);
      const ScanStats stats = insert_scan(tree, marked, clearing, origin, with(-1.0, threads));
      EXPECT_EQ(stats.points, marked.size() + clearing.size());
      EXPECT_EQ(stats.occupied, occupied.size());
      EXPECT_EQ(stats.free, free.size());
    }
    EXPECT_EQ(ours(tree), theirs(reference)) << threads << " threads";
  }
}

// The bridge: our tree and OctoMap's, node for node, both ways and through .ot and .bt files
// written and read by OctoMap itself.
TEST(OctomapBridge, ConversionsAndFiles) {
  Octree tree(0.05);
  octomap::OcTree reference(0.05);
  for (int s = 0; s < 3; ++s) {
    const ScanPoint origin(0.2f * s, 0.1f, 1.2f);
    const auto scan = random_scan(origin, 3000, 1.5);
    octomap::Pointcloud cloud;
    for (const ScanPoint& p : scan) cloud.push_back(p.x(), p.y(), p.z());
    reference.insertPointCloud(cloud, octomap::point3d(origin.x(), origin.y(), origin.z()));
    insert_scan(tree, scan, origin);
  }
  ASSERT_EQ(ours(tree), theirs(reference));
  octomap::OcTree converted(0.1);
  to_octomap(tree, converted);
  EXPECT_EQ(theirs(converted), theirs(reference));
  EXPECT_EQ(converted.size(), reference.size());
  EXPECT_EQ(converted.getResolution(), 0.05);
  EXPECT_FLOAT_EQ(converted.getClampingThresMaxLog(), reference.getClampingThresMaxLog());
  const Octree back = from_octomap(reference);
  EXPECT_EQ(ours(back), theirs(reference));
  EXPECT_EQ(back.node_count(), reference.size());
  EXPECT_EQ(back.model().hit, tree.model().hit);

  const std::string dir = ::testing::TempDir();
  save_octree(tree, dir + "ours.ot");
  EXPECT_EQ(ours(load_octree(dir + "ours.ot")), theirs(reference));
  std::unique_ptr<octomap::AbstractOcTree> read(octomap::AbstractOcTree::read(dir + "ours.ot"));
  ASSERT_NE(dynamic_cast<octomap::OcTree*>(read.get()), nullptr);
  EXPECT_EQ(theirs(*dynamic_cast<octomap::OcTree*>(read.get())), theirs(reference));
  // .bt keeps occupied / free only: compare with OctoMap's own .bt of the same tree.
  save_octree(tree, dir + "ours.bt");
  ASSERT_TRUE(reference.writeBinary(dir + "theirs.bt"));
  octomap::OcTree theirs_bt(0.1);
  ASSERT_TRUE(theirs_bt.readBinary(dir + "theirs.bt"));
  EXPECT_EQ(ours(load_octree(dir + "ours.bt")), theirs(theirs_bt));
  EXPECT_EQ(ours(load_octree(dir + "theirs.bt")), theirs(theirs_bt));
  EXPECT_GT(theirs(theirs_bt).size(), 100u);

  // Empty trees, and bad files: a clear error naming the file.
  Octree empty(0.1);
  octomap::OcTree none(0.2);
  to_octomap(empty, none);
  EXPECT_EQ(none.size(), 0u);
  EXPECT_TRUE(from_octomap(none).empty());
  EXPECT_THROW(load_octree(dir + "missing.ot"), std::runtime_error);
  EXPECT_THROW(save_octree(tree, dir + "tree.txt"), std::runtime_error);
  std::ofstream(dir + "garbage.bt") << "not an octree";
  std::ofstream(dir + "garbage.ot") << "not an octree";
  EXPECT_THROW(load_octree(dir + "garbage.bt"), std::runtime_error);
  EXPECT_THROW(load_octree(dir + "garbage.ot"), std::runtime_error);
  std::stringstream truncated;
  tree.write_nodes(truncated);
  std::string bytes = truncated.str();
  std::stringstream half(bytes.substr(0, bytes.size() / 2));
  EXPECT_THROW(Octree::read_nodes(half, 0.05), std::runtime_error);
  try {
    load_octree(dir + "missing.ot");
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.ot"), std::string::npos);
  }
}

// OctoMap's readers took a file cut short (the nodes they could not read filled with whatever
// the stream gave) and a header of size 0 followed by a data section (read as an empty map):
// both loaded without a word. Every cut of a saved file, and those headers, are refused now.
// An empty map round-trips, ours and OctoMap's: plan_demo read back the node's octree saved
// before the first cloud and was refused ("the data section ends before its last node").
TEST(OctomapBridge, EmptyTreesRoundTrip) {
  const std::string dir = ::testing::TempDir();
  for (const std::string ext : {".bt", ".ot"}) {
    save_octree(Octree(0.05), dir + "empty" + ext);
    const Octree back = load_octree(dir + "empty" + ext);
    EXPECT_TRUE(back.empty()) << ext;
    EXPECT_EQ(back.resolution(), 0.05) << ext;
    octomap::OcTree theirs_empty(0.05);
    ext == ".bt" ? theirs_empty.writeBinary(dir + "theirs" + ext) : theirs_empty.write(dir + "theirs" + ext);
    EXPECT_TRUE(load_octree(dir + "theirs" + ext).empty()) << ext;
  }
}

TEST(OctomapBridge, CutOrMisdeclaredFilesAreRefused) {
  Octree tree(0.05);
  insert_scan(tree, random_scan(ScanPoint(0.0f, 0.0f, 1.0f), 500, 1.0), ScanPoint(0.0f, 0.0f, 1.0f));
  const std::string dir = ::testing::TempDir();
  for (const std::string ext : {".ot", ".bt"}) {
    save_octree(tree, dir + "whole" + ext);
    std::ifstream in(dir + "whole" + ext, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::size_t data = bytes.find("data\n") + 5;
    ASSERT_GT(ours(load_octree(dir + "whole" + ext)).size(), 10u) << ext;  // the whole file loads
    for (const std::size_t cut : {data + 1, (data + bytes.size()) / 2, bytes.size() - 1}) {
      std::ofstream(dir + "cut" + ext, std::ios::binary) << bytes.substr(0, cut);
      EXPECT_THROW(load_octree(dir + "cut" + ext), std::runtime_error) << ext << " cut at " << cut << " of " << bytes.size();
    }
    std::ofstream(dir + "longer" + ext, std::ios::binary) << bytes << "more";
    EXPECT_THROW(load_octree(dir + "longer" + ext), std::runtime_error) << ext;
    std::string zero = bytes;
    const std::size_t size_at = zero.find("size ");
    zero.replace(size_at, zero.find('\n', size_at) - size_at, "size 0");
    std::ofstream(dir + "zero" + ext, std::ios::binary) << zero;
    EXPECT_THROW(load_octree(dir + "zero" + ext), std::runtime_error) << ext;
  }
}

// Points a denormal distance from the sensor but in another voxel (found by the point_cloud fuzz
// target): the ray's float length underflowed to 0, its direction became infinities and NaN,
// and the voxel walk never ended. They are inserted now (their end voxels occupied) at once.
TEST(OctreeBadInput, DenormalRaysEnd) {
  const std::vector<ScanPoint> points = {ScanPoint(-8.82818e-44f, 8.82818e-44f, -0.0f), ScanPoint(0.0f, -0.0f, -1.77965e-43f),
                                         ScanPoint(1e-45f, 1e-45f, 1e-45f), ScanPoint(-1e-45f, 0.0f, 1e-45f)};
  auto done = std::async(std::launch::async, [&] {
    Octree tree(0.05);
    ScanOptions options;
    options.threads = 1;
    insert_scan(tree, points, ScanPoint::Zero(), options);
    return tree.leaves().size();
  });
  if (done.wait_for(std::chrono::seconds(10)) != std::future_status::ready) {
    ADD_FAILURE() << "the scan of four denormal points did not end";
    std::_Exit(1);  // the walk cannot be stopped from here
  }
  EXPECT_GE(done.get(), 1u);
}

TEST(OctreeBadInput, ResolutionAndPoints) {
  EXPECT_THROW(Octree(0.0), std::invalid_argument);
  EXPECT_THROW(Octree(-0.1), std::invalid_argument);
  EXPECT_THROW(Octree(std::nan("")), std::invalid_argument);
  Octree tree(0.05);
  EXPECT_EQ(insert_scan(tree, {}, ScanPoint::Zero()).points, 0u);
  EXPECT_TRUE(tree.empty());
  const float nan = std::nanf("");
  const ScanStats s = insert_scan(tree, {ScanPoint(nan, 0, 0), ScanPoint(1e9f, 0, 0), ScanPoint(-1e9f, 1, 1)}, ScanPoint::Zero());
  EXPECT_EQ(s.skipped_invalid, 1u);
  EXPECT_EQ(s.skipped_outside, 2u);
  EXPECT_TRUE(tree.empty());
}

}  // namespace
}  // namespace bvh_collision
