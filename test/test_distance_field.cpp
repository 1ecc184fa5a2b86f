// OctreeDistanceField (octree/distance_field.h) against brute force over the tree's occupied
// cubes: its bound never exceeds the true distance from a point to every occupied cube (random
// points, points on voxel faces and corners, next to pruned blocks), it is the exact transform's
// (the squared centre distance to the nearest occupied voxel, found by brute force), it is never
// more than 2 sqrt(3) voxels loose under the cap, and it says nothing (0) outside its box.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <sstream>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/robot/package_resolver.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/octree/distance_field.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/octree/voxel_set.h"
#include "checker_fixtures.h"
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

// The grid's own occupancy answers "does this ball meet an occupied cube?" exactly: against the
// brute-force distance to every occupied leaf (the pruned block included), balls on faces and
// corners and touching cubes; nothing when the ball leaves the grid.
TEST(OctreeDistanceField, BallTestEqualsBruteForce) {
  for (const std::uint64_t seed : {4u, 5u}) {
    const Octree tree = scene(seed);
    const double res = tree.resolution(), cap = 0.3;
    const Vec3 lo(-0.5, -0.45, -0.5), hi(0.5, 0.55, 0.45);
    const OctreeDistanceField field = OctreeDistanceField::build(tree, lo, hi, cap);
    std::mt19937_64 rng(seed + 20);
    std::uniform_real_distribution<double> x(lo.x(), hi.x()), y(lo.y(), hi.y()), z(lo.z(), hi.z()), radius(0.0, 0.2);
    std::uniform_int_distribution<int> face(-9, 9);
    int meets = 0, misses = 0;
    for (int i = 0; i < test::sized(3000); ++i) {
      Vec3 p(x(rng), y(rng), z(rng));
      if (i % 3 == 1) p.x() = face(rng) * res;
      if (i % 3 == 2) p = Vec3(face(rng), face(rng), face(rng)) * res;
      const double d = brute_force(tree, p).distance;
      // Half the balls just reach their nearest cube (touching counts).
      const double r = i % 2 == 0 ? std::min(d, 0.25) : radius(rng);
      const std::optional<bool> answer = field.ball_meets_occupied(p, r);
      ASSERT_TRUE(answer.has_value()) << "p = " << p.transpose() << ", r = " << r;
      if (d <= r) {
        ASSERT_TRUE(*answer) << "p = " << p.transpose() << ", r = " << r << ", d = " << d;
      }
      if (*answer) {
        ASSERT_LE(d, r * (1 + 1e-12) + 1e-12) << "p = " << p.transpose() << ", r = " << r;
      }
      ++(*answer ? meets : misses);
    }
    EXPECT_GT(meets, 100);
    EXPECT_GT(misses, 100);
    EXPECT_FALSE(field.ball_meets_occupied(Vec3(0.5, 0.0, 0.0), cap + 5 * res).has_value());  // leaves the grid
    EXPECT_FALSE(field.ball_meets_occupied(Vec3(2.0, 0.0, 0.0), 0.01).has_value());
  }
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

// The revision that keeps a field with its tree: every change gives a new one, a copy keeps it.
TEST(OctreeRevision, EveryChangeGivesANewOneAndACopyKeepsIt) {
  Octree tree(0.05);
  std::uint64_t last = tree.revision();
  auto changed = [&] {
    const bool fresh = tree.revision() != last;
    last = tree.revision();
    return fresh;
  };
  tree.update(key_at(1, 2, 3), true);
  EXPECT_TRUE(changed());
  tree.update_sorted({key_at(4, 4, 4)}, true);
  EXPECT_TRUE(changed());
  const Octree copy = tree;
  EXPECT_EQ(copy.revision(), tree.revision());
  tree.clear_box(Vec3::Constant(-1.0), Vec3::Constant(1.0));
  EXPECT_TRUE(changed());
  EXPECT_NE(copy.revision(), tree.revision());
  tree.update(key_at(1, 2, 3), true);
  EXPECT_TRUE(changed());
  tree.clear();
  EXPECT_TRUE(changed());
  std::stringstream stream;
  copy.write_nodes(stream);
  const Octree read = Octree::read_nodes(stream, 0.05);
  EXPECT_NE(read.revision(), copy.revision());  // equal voxels, but no revision is ever reused
  EXPECT_NE(Octree(0.05).revision(), Octree(0.05).revision());
}

TEST(OctreeDistanceField, TheEnvironmentKeepsItUntilTheOctreeChanges) {
  Environment env(0.05);
  env.octree().update(key_at(3, 3, 3), true);
  const auto a = env.octree_distance_field(Vec3::Constant(-0.5), Vec3::Constant(0.5), 0.2);
  ASSERT_NE(a, nullptr);
  EXPECT_EQ(env.octree_distance_field(Vec3::Constant(-0.4), Vec3::Constant(0.5), 0.1), a);  // covered
  const Environment copy = env;
  EXPECT_EQ(copy.octree_distance_field(Vec3::Constant(-0.5), Vec3::Constant(0.5), 0.2), a);  // shared
  EXPECT_NE(env.octree_distance_field(Vec3::Constant(-0.6), Vec3::Constant(0.5), 0.2), a);  // a larger box
  env.octree().update(key_at(-3, 3, 3), true);
  const auto b = env.octree_distance_field(Vec3::Constant(-0.5), Vec3::Constant(0.5), 0.2);
  ASSERT_NE(b, nullptr);
  EXPECT_NE(b, a);
  EXPECT_LE(b->lower_bound(Vec3(-0.125, 0.175, 0.175)), 0.0);  // the new voxel is seen
  EXPECT_EQ(env.octree_distance_field(Vec3::Constant(-50.0), Vec3::Constant(50.0), 0.2), nullptr);  // too many cells
  env.octree().update(key_at(-4, 3, 3), true);
  EXPECT_EQ(env.octree_distance_field(Vec3::Constant(-0.5), Vec3::Constant(0.5), 0.2, 1 << 24, false), nullptr);
  const auto c = env.octree_distance_field(Vec3::Constant(-0.5), Vec3::Constant(0.5), 0.2);
  EXPECT_EQ(env.octree_distance_field(Vec3::Constant(-0.5), Vec3::Constant(0.5), 0.2, 1 << 24, false), c);
}

// A field follows the voxels whose occupancy flipped exactly as a build of the new tree would:
// voxels turned occupied and freed (in clusters, alone, inside the pruned block, which expands, and
// outside the grid), over several rounds, each updated field equal to a build cell for cell. Small
// rounds recompute blocks; large ones (a fifth of the occupied voxels freed) reach more than an
// eighth of the grid and are built anew.
TEST(OctreeDistanceField, AnUpdateFollowsTheFlippedVoxelsAsABuildWould) {
  for (const std::uint64_t seed : {7u, 8u}) {
    Octree tree = scene(seed);
    const Vec3 lo = Vec3::Constant(-1.5), hi = Vec3::Constant(1.5);
    const double cap = 0.2;
    OctreeDistanceField field = OctreeDistanceField::build(tree, lo, hi, cap);
    std::mt19937_64 rng(seed + 40);
    std::uniform_int_distribution<int> u(-20, 19), small(0, 3);
    int by_blocks = 0, built = 0;
    for (int round = 0; round < 8; ++round) {
      const bool large = round % 2 == 1;
      std::vector<OctreeKey> flipped;
      VoxelSet add, free;
      const int cx = 8 * (round - 4), cy = u(rng), cz = u(rng);
      for (int i = 0; i < 40; ++i) add.insert(key_at(cx + small(rng), cy + small(rng), cz + small(rng)));
      add.insert(key_at(400, 0, 0));  // outside the grid
      free.insert(key_at(2 + round % 4, 3, 4));  // inside the pruned block
      for (const Octree::Leaf& leaf : tree.leaves()) {
        if (large && tree.occupied(leaf.log_odds) && std::uniform_int_distribution<int>(0, 4)(rng) == 0) free.insert(leaf.key);
      }
      if (large) {
        for (int i = 0; i < 10; ++i) add.insert(key_at(u(rng), u(rng), u(rng)));
      }
      free.erase_all(add);
      // A miss frees an occupied voxel in a few updates: each round repeats them.
      for (int k = 0; k < 4; ++k) tree.update_sorted(free.sorted_keys(), false, &flipped);
      tree.update_sorted(add.sorted_keys(), true, &flipped);
      OctreeDistanceField::UpdateWork work;
      field = field.updated(tree, flipped, &work);
      ASSERT_TRUE(field.same_values(OctreeDistanceField::build(tree, lo, hi, cap))) << "seed " << seed << ", round " << round;
      EXPECT_GT(work.flipped, 0u);
      by_blocks += !work.rebuilt && work.blocks > 0;
      built += work.rebuilt;
    }
    EXPECT_GE(by_blocks, 3);
    EXPECT_GE(built, 1);
  }
}

// The work of an update is bounded by the change, not the map: on a 3 m box at 2 cm (4.4 million
// cells), one flipped voxel recomputes at most the blocks its reach touches (a 3 x 3 x 3 of 16^3
// cells at this cap), a cluster of 500 about as many, and the cells read are their windows'.
TEST(OctreeDistanceField, AnUpdateRecomputesTheBlocksTheChangeReachesNotTheMap) {
  Octree tree(0.02);
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> u(-70, 69);
  for (int i = 0; i < 3000; ++i) tree.update(key_at(u(rng), u(rng), u(rng)), true);
  const Vec3 lo = Vec3::Constant(-1.5), hi = Vec3::Constant(1.5);
  const double cap = 0.1;
  const OctreeDistanceField field = OctreeDistanceField::build(tree, lo, hi, cap);
  ASSERT_GT(field.cells(), 4000000u);
  std::vector<OctreeKey> one;
  tree.update_sorted({key_at(5, 5, 5)}, true, &one);
  ASSERT_EQ(one.size(), 1u);
  OctreeDistanceField::UpdateWork work;
  const OctreeDistanceField a = field.updated(tree, one, &work);
  EXPECT_TRUE(a.same_values(OctreeDistanceField::build(tree, lo, hi, cap)));
  // reach = ceil(sqrt(clamp)) = 8 voxels at this cap: 17 cells across, within 3 blocks a side.
  EXPECT_LE(work.blocks, 27u);
  EXPECT_LE(work.cells, 27u * 4096u);
  EXPECT_LE(work.window_cells, 27u * 32u * 32u * 32u);
  const OctreeDistanceField::UpdateWork for_one = work;
  VoxelSet cluster;
  for (int i = 0; i < 500; ++i) cluster.insert(key_at(30 + u(rng) % 8, -20 + u(rng) % 8, 10 + u(rng) % 8));
  std::vector<OctreeKey> flipped;
  tree.update_sorted(cluster.sorted_keys(), true, &flipped);
  const OctreeDistanceField b = a.updated(tree, flipped, &work);
  EXPECT_TRUE(b.same_values(OctreeDistanceField::build(tree, lo, hi, cap)));
  EXPECT_LE(work.blocks, 64u);  // a 16-voxel cube of changes and its reach: 4 blocks a side at most
  EXPECT_LT(work.cells * 10, field.cells());
  std::printf("grid %zu cells; one voxel: %zu blocks, %zu cells written, %zu read; %zu voxels: %zu blocks, %zu written, %zu read\n",
              field.cells(), for_one.blocks, for_one.cells, for_one.window_cells, work.flipped, work.blocks, work.cells,
              work.window_cells);
}

// The environment's kept field follows a scan's flipped voxels (note_octree_changes): the field it
// answers after each scan equals a build of the new tree; a note that does not start at the kept
// field's revision (a change the note does not cover) is not followed but rebuilt.
TEST(OctreeDistanceField, TheEnvironmentsFieldFollowsAScan) {
  Environment env(0.05);
  const Vec3 lo = Vec3::Constant(-0.5), hi = Vec3::Constant(0.5);
  env.octree().update(key_at(3, 3, 3), true);
  ASSERT_NE(env.octree_distance_field(lo, hi, 0.2), nullptr);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (int scan = 0; scan < 5; ++scan) {
    std::vector<ScanPoint> points;
    for (int i = 0; i < 200; ++i) points.emplace_back(u(rng), u(rng), 0.3 + 0.2 * u(rng));
    const std::uint64_t from = env.octree().revision();
    ScanStats stats = insert_scan(env.octree(), points, ScanPoint(0.0, 0.0, -0.8));
    EXPECT_GT(stats.flipped.size(), 0u);
    env.note_octree_changes(from, std::move(stats.flipped));
    if (scan == 3) env.octree().update(key_at(-2, -2, -2), true);  // a change the note does not cover
    const auto field = env.octree_distance_field(lo, hi, 0.2);
    ASSERT_NE(field, nullptr);
    EXPECT_TRUE(field->same_values(OctreeDistanceField::build(env.octree(), lo, hi, 0.2))) << "scan " << scan;
  }
}

// A field made the field of a tree several changes later, in place on its grid, from the union
// of the changes' lists (voxels flipped twice among them, and outside the grid), equals a build;
// the field it was made from keeps its values, holding only the pages that changed; a second
// field made from that one (no longer the grid's latest) is a copy, with the same values.
TEST(OctreeDistanceField, SeveralChangesInPlaceEqualABuildAndTheOldFieldKeepsItsValues) {
  Octree tree(0.05);
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<int> u(-12, 11);
  for (int i = 0; i < 300; ++i) tree.update(key_at(u(rng), u(rng), u(rng)), true);
  const Vec3 lo = Vec3::Constant(-2.0), hi = Vec3::Constant(2.0);  // 636,056 cells; the changes reach 8 blocks
  std::uniform_int_distribution<int> near(-4, 3);
  const Octree original = tree;
  const OctreeDistanceField field = OctreeDistanceField::build(tree, lo, hi, 0.1);
  std::vector<std::vector<OctreeKey>> lists(3);
  VoxelSet first;
  for (int i = 0; i < 30; ++i) first.insert(key_at(near(rng), near(rng), near(rng)));
  first.insert(key_at(300, 0, 0));  // outside the grid
  tree.update_sorted(first.sorted_keys(), true, &lists[0]);
  for (int k = 0; k < 4; ++k) tree.update_sorted(first.sorted_keys(), false, &lists[1]);  // some back again
  VoxelSet third;
  for (int i = 0; i < 30; ++i) third.insert(key_at(near(rng), near(rng), near(rng)));
  tree.update_sorted(third.sorted_keys(), true, &lists[2]);
  const OctreeDistanceField built = OctreeDistanceField::build(tree, lo, hi, 0.1);
  ASSERT_FALSE(field.same_values(built));
  OctreeDistanceField::UpdateWork work;
  const OctreeDistanceField next = field.updated(tree, {&lists[0], &lists[1], &lists[2]}, &work);
  EXPECT_TRUE(next.same_values(built));
  EXPECT_FALSE(work.rebuilt);
  EXPECT_EQ(work.copied_cells, 0u);
  EXPECT_LT(work.cells * 8, field.cells());
  EXPECT_GT(work.flipped, lists[2].size());
  EXPECT_GT(work.changed_cells, 0u);
  EXPECT_LE(work.changed_cells, work.cells);
  // The old field: its tree's values, and memory of its own only for the pages that changed.
  EXPECT_TRUE(field.same_values(OctreeDistanceField::build(original, lo, hi, 0.1)));
  const std::size_t grid_bytes = next.memory_bytes();
  EXPECT_EQ(OctreeDistanceField::distinct_memory_bytes({&field, &next}), grid_bytes + work.kept_pages * VersionedGrid::kPageBytes);
  EXPECT_LE(work.kept_pages, (work.changed_cells + lists[0].size() + lists[1].size() + lists[2].size()));
  // Made again from the old field: a copy (the grid's file holds the newer values).
  OctreeDistanceField::UpdateWork again;
  const OctreeDistanceField copy = field.updated(tree, {&lists[0], &lists[1], &lists[2]}, &again);
  EXPECT_TRUE(copy.same_values(built));
  EXPECT_FALSE(again.rebuilt);
  EXPECT_EQ(again.copied_cells, field.cells());
  EXPECT_TRUE(field.same_values(OctreeDistanceField::build(original, lo, hi, 0.1)));
  EXPECT_TRUE(next.same_values(built));
}

// follow writes a field over in place when nothing else holds its cells (no page kept for it, its
// cells where they were), while an earlier version of the same grid that a reader holds keeps its
// values; with its cells shared by a copy of the field it makes a new version instead.
TEST(OctreeDistanceField, FollowWritesOverAFieldNobodyElseHoldsAndAHeldVersionKeepsItsValues) {
  Octree tree(0.05);
  std::mt19937_64 rng(19);
  std::uniform_int_distribution<int> u(-12, 11), near(-4, 3);
  for (int i = 0; i < 300; ++i) tree.update(key_at(u(rng), u(rng), u(rng)), true);
  const Vec3 lo = Vec3::Constant(-2.0), hi = Vec3::Constant(2.0);
  auto change = [&](std::vector<OctreeKey>& list) {
    VoxelSet keys;
    for (int i = 0; i < 20; ++i) keys.insert(key_at(near(rng), near(rng), near(rng)));
    tree.update_sorted(keys.sorted_keys(), true, &list);
  };
  const Octree first_tree = tree;
  const OctreeDistanceField held = OctreeDistanceField::build(tree, lo, hi, 0.1);
  std::vector<OctreeKey> one, two, three;
  change(one);
  OctreeDistanceField::UpdateWork work;
  OctreeDistanceField field = held.updated(tree, one, &work);  // in place: `held` keeps its pages
  ASSERT_EQ(work.copied_cells, 0u);
  const Octree second_tree = tree;
  change(two);
  const OctreeDistanceField before = field;  // a copy shares the cells: a new version is made
  field.follow(tree, {&two}, &work);
  EXPECT_TRUE(field.same_values(OctreeDistanceField::build(tree, lo, hi, 0.1)));
  EXPECT_TRUE(before.same_values(OctreeDistanceField::build(second_tree, lo, hi, 0.1)));
  change(three);
  const std::size_t held_bytes = OctreeDistanceField::distinct_memory_bytes({&held, &field}) - field.memory_bytes();
  field.follow(tree, {&three}, &work);  // nobody else holds its cells now: written over
  EXPECT_EQ(work.copied_cells, 0u);
  EXPECT_GT(work.changed_cells, 0u);
  EXPECT_TRUE(field.same_values(OctreeDistanceField::build(tree, lo, hi, 0.1)));
  EXPECT_TRUE(held.same_values(OctreeDistanceField::build(first_tree, lo, hi, 0.1)));
  EXPECT_TRUE(before.same_values(OctreeDistanceField::build(second_tree, lo, hi, 0.1)));
  // The held versions kept only pages (no grid of their own), and only what the writes reached.
  const std::size_t after = OctreeDistanceField::distinct_memory_bytes({&held, &before, &field}) - field.memory_bytes();
  EXPECT_GE(after, held_bytes);
  EXPECT_LT(after * 4, field.memory_bytes());
}

// Environment checks with the field answer as without it, state by state (at tolerance 0 the
// answers are exact, so equal), on the demo arm amid random boxes, with a moved base, and after
// the octree changes under a kept field.
TEST(OctreeDistanceField, EnvironmentChecksAnswerAsWithoutIt) {
  CheckerOptions options;
  options.padding = 0.01;
  const CollisionChecker checker = test::demo_arm_checker(options);
  Environment env(0.02);
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int box = 0; box < 40; ++box) {
    const Vec3 lo(u(rng), u(rng), 0.5 * (u(rng) + 1.0));
    for (double x = 0; x < 0.1; x += 0.01) {
      for (double y = 0; y < 0.1; y += 0.01) env.octree().update(*env.octree().grid().key(lo + Vec3(x, y, 0.0)), true);
    }
  }
  int cleared_some = 0;
  for (int round = 0; round < 3; ++round) {
    if (round == 1) {  // the kept field is stale now: voxels go, and new ones come near the arm
      env.octree().clear_box(Vec3(-1.0, -1.0, 0.0), Vec3(0.0, 1.0, 1.0));
      for (double x = -0.4; x < 0.4; x += 0.02) {
        for (double y = -0.4; y < 0.4; y += 0.02) env.octree().update(*env.octree().grid().key(Vec3(x, y, 0.45)), true);
      }
    }
    for (int i = 0; i < test::sized(600); ++i) {
      const std::vector<double> q = random_configuration(checker.model(), rng);
      EnvironmentRequest plain;
      plain.distance_field = EnvironmentRequest::DistanceField::kOff;
      if (round == 2) plain.root_pose.t = Vec3(0.1, -0.2, 0.05);
      plain.all_links = i % 2 == 0;
      EnvironmentRequest with = plain;
      with.distance_field = EnvironmentRequest::DistanceField::kBuild;
      const EnvironmentResult a = checker.check_environment(q.data(), env, plain);
      const EnvironmentResult b = checker.check_environment(q.data(), env, with);
      ASSERT_EQ(a.collision, b.collision) << "round " << round << ", state " << i;
      if (plain.all_links) {
        ASSERT_EQ(a.contacts.size(), b.contacts.size()) << "round " << round << ", state " << i;
      }
      // That the field did clear links: the same test the check makes, on the link centres (a
      // copy builds its own, so the environment's kept field stays the checker's).
      if (i % 150 != 0) continue;
      const Environment probe = env;
      const Vec3 reach = Vec3::Constant(checker.collision_model().reach());
      const auto field = probe.octree_distance_field(plain.root_pose.t - reach, plain.root_pose.t + reach, 0.3);
      ASSERT_NE(field, nullptr);
      std::vector<Transform> poses;
      checker.collision_model().kinematics().compute(q.data(), poses);
      for (std::size_t l = 0; l < poses.size(); ++l) {
        const LinkBound& bound = checker.collision_model().bounds()[l];
        if (bound.radius < 0) continue;
        cleared_some += field->lower_bound(plain.root_pose * (poses[l] * bound.center)) > bound.radius + 0.01;
      }
    }
  }
  EXPECT_GT(cleared_some, 0);
}

// check_batch checks the links no joint moves once (the demo arm's base): with a slab through
// the base every state collides, with the slab 1 mm below it the batch answers as one state at a
// time; with the distance field kept and without.
TEST(OctreeDistanceField, BatchesCheckTheFixedLinksOnceAndAnswerAsOneByOne) {
  const CollisionChecker checker = test::demo_arm_checker();
  std::mt19937_64 rng(37);
  std::vector<double> flat;
  const int count = test::sized(400);
  for (int i = 0; i < count; ++i) {
    const std::vector<double> q = random_configuration(checker.model(), rng);
    flat.insert(flat.end(), q.begin(), q.end());
  }
  for (const double slab : {0.01, -0.03}) {  // the base is the box z in [0, 0.1]; slab voxels 2 cm
    Environment env(0.02);
    for (double x = -0.6; x < 0.6; x += 0.01) {
      for (double y = -0.6; y < 0.6; y += 0.01) env.octree().update(*env.octree().grid().key(Vec3(x, y, slab)), true);
    }
    for (int box = 0; box < 20; ++box) {
      const Vec3 c(std::uniform_real_distribution<double>(-0.8, 0.8)(rng), std::uniform_real_distribution<double>(-0.8, 0.8)(rng),
                   std::uniform_real_distribution<double>(0.2, 0.9)(rng));
      env.octree().update(*env.octree().grid().key(c), true);
    }
    for (const bool field : {false, true}) {
      if (field) {
        EnvironmentRequest build;
        build.distance_field = EnvironmentRequest::DistanceField::kBuild;
        checker.check_environment(flat.data(), env, build);
      }
      BatchRequest request;
      request.self = false;
      const std::vector<char> batch = checker.check_batch(flat.data(), count, &env, request);
      int colliding = 0;
      for (int i = 0; i < count; ++i) {
        EnvironmentRequest without;
        without.distance_field = EnvironmentRequest::DistanceField::kOff;
        const bool one = checker.check_environment(flat.data() + i * checker.model().variable_count(), env, without).collision;
        ASSERT_EQ(batch[i] != 0, one) << "slab at " << slab << ", state " << i << ", field " << field;
        colliding += one;
      }
      if (slab > 0) {
        EXPECT_EQ(colliding, count);
      } else {
        EXPECT_LT(colliding, count);
        EXPECT_GT(colliding, 0);
      }
    }
  }
}

}  // namespace
}  // namespace bvh_collision
