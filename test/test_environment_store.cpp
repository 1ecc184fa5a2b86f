// Concurrency of the node's core: EnvironmentStore snapshots against a writer that replaces a
// whole generation of objects and voxels at once (a reader must never see a mix), a failed change
// that must leave nothing behind, and CollisionChecker::check_batch on both cores against one
// check per state.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <tuple>
#include <vector>
#include <random>
#include <string>
#include <thread>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/world/environment_store.h"
#include "bvh_collision/octree/scan.h"
#include "checker_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

constexpr int kObjects = 5;

// Generation g: kObjects boxes named "g<g>_<k>" and one occupied voxel at x = g * resolution.
void write_generation(Environment& env, int g) {
  env.clear_objects();
  for (int k = 0; k < kObjects; ++k) {
    env.add_object("g" + std::to_string(g) + "_" + std::to_string(k), ObjectShape::box(Vec3(0.1, 0.1, 0.1)),
                   Transform::Translation(Vec3(k, g, 0)));
  }
  env.octree().clear();
  insert_points(env.octree(), {ScanPoint(0.05f * g + 0.025f, 0.025f, 0.025f)});
}

// The generation a snapshot holds, or -1 when it mixes generations.
int generation_of(const Environment& env) {
  if (env.objects().size() != static_cast<std::size_t>(kObjects)) return -1;
  const std::string& first = env.objects()[0].id;
  const int g = std::stoi(first.substr(1, first.find('_') - 1));
  for (int k = 0; k < kObjects; ++k) {
    if (env.objects()[k].id != "g" + std::to_string(g) + "_" + std::to_string(k)) return -1;
  }
  const auto leaves = env.octree().leaves();
  if (leaves.size() != 1 || !env.octree().locate(Vec3(0.05 * g + 0.025, 0.025, 0.025))) return -1;
  return g;
}

TEST(EnvironmentStore, ReadersNeverSeeAHalfWrittenEnvironment) {
  Environment initial(0.05);
  write_generation(initial, 0);
  EnvironmentStore store(std::move(initial));
  std::atomic<bool> stop{false};
  std::atomic<int> mixed{0}, reads{0}, went_back{0};
  auto reader = [&] {
    int last = 0;
    while (!stop) {
      const auto env = store.snapshot();
      const int g = generation_of(*env);
      mixed += g < 0;
      went_back += g >= 0 && g < last;
      last = std::max(last, g);
      ++reads;
    }
  };
  std::thread r1(reader), r2(reader);
  for (int g = 1; g <= 300; ++g) store.modify([g](Environment& env) { write_generation(env, g); });
  stop = true;
  r1.join();
  r2.join();
  EXPECT_EQ(mixed, 0);
  EXPECT_EQ(went_back, 0);
  EXPECT_GT(reads, 100);
  EXPECT_EQ(generation_of(*store.snapshot()), 300);
  EXPECT_EQ(store.version(), 301u);  // the initial snapshot is version 1
}

TEST(EnvironmentStore, AChangeThatThrowsLeavesNothingBehind) {
  Environment initial(0.05);
  write_generation(initial, 0);
  EnvironmentStore store(std::move(initial));
  const auto before = store.snapshot();
  EXPECT_THROW(store.modify([](Environment& env) {
                 env.add_object("half", ObjectShape::sphere(0.1), Transform());
                 env.octree().clear();
                 env.add_object("bad", ObjectShape::sphere(-1.0), Transform());  // throws
               }),
               std::invalid_argument);
  EXPECT_EQ(store.snapshot(), before) << "a failed change published a snapshot";
  EXPECT_EQ(store.version(), 1u);
  // The working copy went back too: the next change starts from generation 0.
  const std::size_t objects = store.modify([](Environment& env) { return env.objects().size(); });
  EXPECT_EQ(objects, static_cast<std::size_t>(kObjects));
  EXPECT_EQ(generation_of(*store.snapshot()), 0);
  EXPECT_EQ(store.snapshot()->find_object("half"), nullptr);
}

// --- Shared snapshots: a change copies what it touches ---

// (index, depth, log-odds) of every leaf: two trees with equal lists hold the same voxels.
std::vector<std::tuple<std::uint64_t, int, float>> leaf_list(const Octree& tree) {
  std::vector<std::tuple<std::uint64_t, int, float>> out;
  for (const auto& l : tree.leaves()) out.emplace_back(l.index, l.depth, l.log_odds);
  std::sort(out.begin(), out.end());
  return out;
}

// Scattered occupied voxels (no pruning): a map of many pages.
Environment scattered_map(int points, std::uint64_t seed) {
  Environment env(0.02);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  std::vector<ScanPoint> cloud(points);
  for (auto& p : cloud) p = ScanPoint(u(rng), u(rng), 0.5f * u(rng) + 0.5f);
  insert_points(env.octree(), cloud);
  return env;
}

TEST(SharedSnapshots, ClearingOneVoxelCopiesAFewPagesNotTheMap) {
  EnvironmentStore store(scattered_map(100000, 1));
  const auto old = store.snapshot();
  const auto old_leaves = leaf_list(old->octree());
  const auto voxel = old->octree().leaves().front();
  const Vec3 centre = old->octree().cube_min(voxel.key) + Vec3::Constant(0.5 * old->octree().cube_size(voxel.depth));
  store.modify([&](Environment& env) { env.octree().clear_box(centre, centre); });
  const auto now = store.snapshot();

  const std::size_t map = old->octree().memory_bytes();
  const std::size_t both = Octree::distinct_memory_bytes({&old->octree(), &now->octree()});
  RecordProperty("map_bytes", std::to_string(map));
  RecordProperty("added_bytes", std::to_string(both - map));
  EXPECT_GT(map, std::size_t(2) << 20);
  // The path to the voxel (17 nodes, at most 17 pages of 6 KiB) and a page table.
  EXPECT_LT(both - map, 17 * 6144 + map / 50) << "the change copied " << both - map << " of " << map << " bytes";
  EXPECT_EQ(leaf_list(old->octree()), old_leaves) << "the change reached a snapshot a reader holds";

  Octree reference = scattered_map(100000, 1).octree();  // built apart: nothing shared
  reference.clear_box(centre, centre);
  EXPECT_EQ(leaf_list(now->octree()), leaf_list(reference));
  EXPECT_EQ(now->octree().node_count(), reference.node_count());
  EXPECT_FALSE(now->octree().locate(centre) && now->octree().locate(centre)->depth == kOctreeDepth);
}

// Scans into a store, each followed by the map's distance field, as the node's cloud thread does
// (session/scan_update.cpp): every field is made in place on the grid of the one before, from the
// voxels the scan changed, with no copy of the grid, whether or not a reader holds the earlier
// one; a held field never changes under its reader and holds memory of its own only for the pages
// changed since (a pinned version too: its memory is what changed, not a grid). Every field
// equals a build of its snapshot's tree.
TEST(SharedSnapshots, TheNextDistanceFieldIsMadeInPlaceAndAHeldOneKeepsOnlyWhatChanged) {
  EnvironmentStore store(scattered_map(20000, 4));
  const Vec3 lo(-1.2, -1.2, -0.2), hi(1.2, 1.2, 1.2);
  const double cap = 0.1;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(-0.2f, 0.2f);
  auto scan = [&](float x) {
    std::vector<ScanPoint> cloud(300);
    for (auto& p : cloud) p = ScanPoint(x + u(rng), u(rng), 0.6f + u(rng));
    return store.modify([&](Environment& env) {
      const std::uint64_t from = env.octree().revision();
      ScanStats stats = insert_scan(env.octree(), cloud, ScanPoint(0.0f, 0.0f, 0.0f));
      env.note_octree_changes(from, std::move(stats.flipped));
      EXPECT_NE(env.octree_distance_field(lo, hi, cap), nullptr);
      return env.octree_field_work().value();
    });
  };
  auto field_of = [&](const Environment& env) { return env.octree_distance_field(lo, hi, cap, std::size_t(1) << 24, false); };
  auto equals_a_build = [&](const Environment& env) {
    const auto field = field_of(env);
    return field && field->same_values(OctreeDistanceField::build(env.octree(), lo, hi, cap));
  };
  store.modify([&](Environment& env) { env.octree_distance_field(lo, hi, cap); });
  const auto first = field_of(*store.snapshot());
  const std::size_t grid = first->cells(), grid_bytes = first->memory_bytes();
  ASSERT_GT(grid, 1000000u);
  int copies = 0;
  auto scans = [&](int n, float x0, float dx) {
    for (int i = 0; i < n; ++i) {
      const OctreeDistanceField::UpdateWork work = scan(x0 + dx * float(i));
      ASSERT_TRUE(equals_a_build(*store.snapshot())) << "scan " << i;
      ASSERT_FALSE(work.rebuilt) << "scan " << i;
      EXPECT_GT(work.flipped, 0u);
      EXPECT_LT(work.cells * 8, grid);        // the blocks the scans reached, not the map
      copies += work.copied_cells > 0;
    }
  };
  scans(6, -0.8f, 0.3f);
  EXPECT_LE(copies, 1);  // the second grid's making: from then on the fields alternate between two

  // A reader holds a snapshot and its field over three scans: the fields after it are still made
  // in place; its field keeps its tree's values and holds only the pages changed since.
  const auto held = store.snapshot();
  const auto held_field = field_of(*held);
  ASSERT_NE(held_field, nullptr);
  scans(3, 0.5f, -0.4f);
  EXPECT_TRUE(held_field->same_values(OctreeDistanceField::build(held->octree(), lo, hi, cap)));
  EXPECT_LE(copies, 1);  // (none while a reader holds a field)
  std::vector<const OctreeDistanceField*> kept;  // what the map keeps anyway: its pool
  const auto pool = store.snapshot()->pooled_octree_fields();
  for (const auto& f : pool) kept.push_back(f.get());
  const std::size_t map_bytes = OctreeDistanceField::distinct_memory_bytes(kept);
  EXPECT_LE(map_bytes, 2 * grid_bytes + grid_bytes / 4);  // two grids and little more
  kept.push_back(held_field.get());
  const std::size_t own = OctreeDistanceField::distinct_memory_bytes(kept) - map_bytes;
  EXPECT_GT(own, 0u);
  EXPECT_LT(own * 8, grid_bytes);

  // A pinned version, over three scans: its memory beyond the current map is the octree pages and
  // the field pages changed since, far less than a grid (it was a whole grid before).
  const auto t0 = EnvironmentStore::Clock::now();
  const EnvironmentStore::Pin pin = store.pin(std::chrono::seconds(60), t0);
  const auto pinned_field = field_of(*pin.snapshot);
  const std::size_t before = store.pinned_extra_bytes();  // (the pin shares the current map and field)
  EXPECT_LT(before * 100, grid_bytes);
  scans(3, -0.3f, 0.3f);
  const std::size_t extra = store.pinned_extra_bytes();
  EXPECT_GT(extra, before);
  EXPECT_LT(extra * 4, grid_bytes);
  RecordProperty("pinned_extra_over_grid", std::to_string(double(extra) / double(grid_bytes)));
  EXPECT_TRUE(pinned_field->same_values(OctreeDistanceField::build(pin.snapshot->octree(), lo, hi, cap)));
  EXPECT_TRUE(store.release(pin.version));
}

// Scans stream in on one thread (each making the map's field, as the node's cloud thread does)
// while two readers take snapshots, hold them across scans or not, and check that each held field
// equals a build of its snapshot's tree: fields written over, new versions and kept pages never
// show a reader anything but its own map's values.
TEST(SharedSnapshots, ReadersHoldingFieldsWhileScansStreamInSeeTheirOwnMap) {
  EnvironmentStore store(scattered_map(20000, 4));
  const Vec3 lo(-1.2, -1.2, -0.2), hi(1.2, 1.2, 1.2);
  const double cap = 0.1;
  store.modify([&](Environment& env) { env.octree_distance_field(lo, hi, cap); });
  std::atomic<bool> done{false};
  std::atomic<int> checked{0}, wrong{0};
  auto reader = [&](int hold_scans) {
    while (!done) {
      const auto snapshot = store.snapshot();
      const auto field = snapshot->octree_distance_field(lo, hi, cap, std::size_t(1) << 24, false);
      if (field == nullptr) continue;
      const std::uint64_t version = store.version();
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
      while (!done && store.version() < version + std::uint64_t(hold_scans) && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::yield();
      }
      if (!field->same_values(OctreeDistanceField::build(snapshot->octree(), lo, hi, cap))) ++wrong;
      ++checked;
    }
  };
  std::thread short_reader(reader, 0), long_reader(reader, 3);
  int in_place = 0;
  std::mt19937_64 rng(8);
  std::uniform_real_distribution<float> u(-0.1f, 0.1f);
  for (int scan = 0; scan < 40; ++scan) {
    std::vector<ScanPoint> cloud(100);
    const float x = -0.3f + 0.015f * float(scan);
    for (auto& p : cloud) p = ScanPoint(x + u(rng), u(rng), 0.6f + u(rng));
    store.modify([&](Environment& env) {
      const std::uint64_t from = env.octree().revision();
      ScanStats stats = insert_scan(env.octree(), cloud, ScanPoint(0.0f, 0.0f, 0.0f));
      env.note_octree_changes(from, std::move(stats.flipped));
      env.octree_distance_field(lo, hi, cap);
      const auto work = env.octree_field_work().value();
      in_place += !work.rebuilt && work.copied_cells == 0;
    });
    if (scan % 4 == 3) {  // a reader's check between every few scans, however slow the build
      const int before = checked.load();
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
      while (checked.load() == before && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
    }
  }
  done = true;
  short_reader.join();
  long_reader.join();
  EXPECT_GT(checked.load(), 10);
  EXPECT_GE(in_place, 30);  // (not built anew: the fields were written over or made as new versions)
  EXPECT_EQ(wrong.load(), 0);
}

// Four readers each hold a snapshot while scans stream in (each scan re-observes part of the
// map): the snapshots together hold less than twice one map, and none of them changes.
TEST(SharedSnapshots, FourOldSnapshotsHoldLessThanTwoMaps) {
  EnvironmentStore store(scattered_map(100000, 2));
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(-0.3f, 0.3f);
  std::vector<std::pair<std::shared_ptr<const Environment>, decltype(leaf_list(Octree(1.0)))>> held;
  for (int scan = 0; scan < 12; ++scan) {
    std::vector<ScanPoint> cloud(2000);
    for (auto& p : cloud) p = ScanPoint(0.5f + u(rng), u(rng), 0.5f + u(rng));
    store.modify([&](Environment& env) { insert_scan(env.octree(), cloud, ScanPoint(0.0f, 0.0f, 0.5f)); });
    held.emplace_back(store.snapshot(), std::vector<std::tuple<std::uint64_t, int, float>>{});
    if (held.size() > 5) held.erase(held.begin());  // four old ones and the newest
  }
  for (auto& [env, leaves] : held) leaves = leaf_list(env->octree());
  std::vector<const Octree*> trees;
  for (const auto& h : held) trees.push_back(&h.first->octree());
  const std::size_t map = store.snapshot()->octree().memory_bytes();
  const std::size_t all = Octree::distinct_memory_bytes(trees);
  RecordProperty("five_snapshots_over_one_map", std::to_string(double(all) / double(map)));
  EXPECT_LT(all, 2 * map);
  // Later scans left the held snapshots as they were.
  for (int scan = 0; scan < 3; ++scan) {
    store.modify([&](Environment& env) { insert_points(env.octree(), {ScanPoint(0.5f, 0.1f * scan, 0.5f)}); });
  }
  for (const auto& [env, leaves] : held) {
    EXPECT_EQ(leaf_list(env->octree()), leaves);
  }
}

// A reader walking its snapshot while a writer changes the same pages never sees a change
// (run under the sanitizers, this is also where a page written in place would show).
TEST(SharedSnapshots, ReadersWalkTheirSnapshotWhileAWriterChangesIt) {
  EnvironmentStore store(scattered_map(20000, 4));
  std::atomic<bool> stop{false};
  std::atomic<int> changed{0}, walks{0};
  auto reader = [&] {
    while (!stop) {
      const auto env = store.snapshot();
      const auto first = leaf_list(env->octree());
      changed += leaf_list(env->octree()) != first;
      ++walks;
    }
  };
  std::thread r1(reader), r2(reader);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int change = 0; change < 60 || walks < 20; ++change) {
    const Vec3 c(u(rng), u(rng), 0.5 + 0.5 * u(rng));
    store.modify([&](Environment& env) {
      env.octree().clear_box(c - Vec3::Constant(0.1), c + Vec3::Constant(0.1));
      insert_points(env.octree(), {ScanPoint(float(c.x()), float(c.y()), float(c.z()))});
    });
  }
  stop = true;
  r1.join();
  r2.join();
  EXPECT_EQ(changed, 0);
  EXPECT_GE(walks, 20);
}

TEST(SharedSnapshots, ObjectChangesLeaveOtherCopiesAndShareHierarchies) {
  Environment env(0.05);
  env.add_object("a", ObjectShape::box(Vec3(0.1, 0.2, 0.3)), Transform::Translation(Vec3(1, 0, 0)));
  env.add_object("b", ObjectShape::sphere(0.1), Transform());
  const Environment copy = env;
  env.move_object("a", Transform::Translation(Vec3(2, 0, 0)));
  env.remove_object("b");
  env.add_object("c", ObjectShape::sphere(0.2), Transform());
  ASSERT_EQ(copy.objects().size(), 2u);
  EXPECT_EQ(copy.find_object("a")->pose.t.x(), 1.0);
  EXPECT_NE(copy.find_object("b"), nullptr);
  EXPECT_EQ(copy.find_object("c"), nullptr);
  EXPECT_EQ(env.find_object("a")->pose.t.x(), 2.0);
  EXPECT_EQ(env.find_object("a")->mesh, copy.find_object("a")->mesh) << "moving an object rebuilt or copied its hierarchy";
  EXPECT_EQ(env.find_object("b"), nullptr);
}

// One world for one plan: a pinned version answers with the snapshot it pinned, its voxels
// unchanged while scans change the current map; a use renews the pin, and one left unused past
// its timeout, or released, is an error naming the setting. The clock is the test's own.
TEST(PinnedVersions, AnswerTheWorldTheyPinnedUntilReleasedOrExpired) {
  EnvironmentStore store{Environment(0.02)};
  store.modify([](Environment& env) {  // a map of many pages: 8,000 voxels of a rough wall
    for (int y = 0; y < 200; ++y) {
      for (int z = 0; z < 40; ++z) env.octree().update(OctreeKey{{std::uint16_t(33000 + (y * z) % 3), std::uint16_t(32768 + y), std::uint16_t(32768 + z)}}, true);
    }
  });
  const std::size_t voxels = store.snapshot()->octree().leaves().size();
  using Clock = EnvironmentStore::Clock;
  const Clock::time_point t0{};  // the test's clock
  const auto timeout = std::chrono::seconds(2);
  const EnvironmentStore::Pin pin = store.pin(timeout, t0);
  EXPECT_EQ(pin.version, store.version());
  const std::uint64_t revision = pin.snapshot->octree().revision();
  for (int k = 1; k <= 20; ++k) {  // scans after the pin: the current map moves on
    store.modify([&](Environment& env) { env.octree().update(OctreeKey{{std::uint16_t(32768 + k), 32768, 32768}}, true); });
  }
  EXPECT_GT(store.version(), pin.version);
  // Used every second: each use renews it, past the first timeout.
  for (int s = 1; s <= 5; ++s) {
    const auto world = store.pinned(pin.version, t0 + std::chrono::seconds(s));
    EXPECT_EQ(world, pin.snapshot);
    EXPECT_EQ(world->octree().revision(), revision);
    EXPECT_EQ(world->octree().leaves().size(), voxels);
  }
  EXPECT_EQ(store.pins(t0 + std::chrono::seconds(5)), 1u);
  // What it holds beyond the current map: the pages the scans since have copied, not a map.
  EXPECT_GT(store.pinned_extra_bytes(), 0u);
  EXPECT_LT(store.pinned_extra_bytes() * 4, store.snapshot()->octree().memory_bytes());
  // Unused for longer than the timeout: an error that names the setting.
  try {
    store.pinned(pin.version, t0 + std::chrono::seconds(8));
    ADD_FAILURE() << "an expired pin answered";
  } catch (const PinError& e) {
    EXPECT_NE(std::string(e.what()).find("pin_timeout"), std::string::npos) << e.what();
  }
  EXPECT_EQ(store.pins(t0 + std::chrono::seconds(8)), 0u);
  EXPECT_EQ(store.pinned_extra_bytes(), 0u);
  // Released: gone at once; a version never pinned is the same error.
  const EnvironmentStore::Pin again = store.pin(timeout, t0 + std::chrono::seconds(9));
  EXPECT_EQ(again.snapshot, store.snapshot());
  EXPECT_TRUE(store.release(again.version));
  EXPECT_FALSE(store.release(again.version));
  EXPECT_THROW(store.pinned(again.version, t0 + std::chrono::seconds(9)), PinError);
  EXPECT_THROW(store.pinned(12345, t0), PinError);
  EXPECT_THROW(store.pin(std::chrono::seconds(0), t0), std::invalid_argument);
}

TEST(CheckBatch, EqualsOneCheckPerState) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  Environment env(0.04);
  std::vector<ScanPoint> table;
  for (float x = 0.2f; x < 0.8f; x += 0.01f)
    for (float y = -0.4f; y < 0.4f; y += 0.01f) table.emplace_back(x, y, 0.3f);
  insert_scan(env.octree(), table, ScanPoint(0.5f, 0.0f, 1.5f));
  env.add_object("ball", ObjectShape::sphere(0.1), Transform::Translation(Vec3(0.5, -0.3, 0.6)));
  std::mt19937_64 rng(5);
  const std::size_t n = checker.model().variable_count();
  for (std::size_t count : {0u, 1u, 17u, 600u}) {
    std::vector<double> states;
    for (std::size_t i = 0; i < count; ++i) {
      const auto q = random_configuration(checker.model(), rng);
      states.insert(states.end(), q.begin(), q.end());
    }
    BatchRequest request;
    request.root_pose = Transform::Translation(Vec3(0.05, 0.0, 0.0));
    for (int checks = 1; checks <= 3; ++checks) {
      request.self = checks & 1;
      request.environment = checks & 2;
      const std::vector<char> got = checker.check_batch(states.data(), count, &env, request);
      ASSERT_EQ(got.size(), count);
      int colliding = 0;
      for (std::size_t i = 0; i < count; ++i) {
        EnvironmentRequest e;
        e.root_pose = request.root_pose;
        const bool expected = (request.self && checker.check_self(&states[i * n]).collision) ||
                              (request.environment && checker.check_environment(&states[i * n], env, e).collision);
        ASSERT_EQ(static_cast<bool>(got[i]), expected) << "state " << i << " of " << count << ", checks " << checks;
        colliding += expected;
      }
      if (count == 600) {
        EXPECT_GT(colliding, 30) << "checks " << checks;
        EXPECT_LT(colliding, 570) << "checks " << checks;
      }
    }
  }
  BatchRequest needs_env;
  EXPECT_THROW(checker.check_batch(nullptr, 0, nullptr, needs_env), std::invalid_argument);
}

}  // namespace
}  // namespace bvh_collision
