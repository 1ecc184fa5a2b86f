// Concurrency of the node's core: EnvironmentStore snapshots against a writer that replaces a
// whole generation of objects and voxels at once (a reader must never see a mix), a failed change
// that must leave nothing behind, and CollisionChecker::check_batch on both cores against one
// check per state.
#include <gtest/gtest.h>

#include <atomic>
#include <random>
#include <string>
#include <thread>

#include "bvh_collision/checker/collision_checker.h"
#include "bvh_collision/checker/environment_store.h"
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
  EXPECT_EQ(store.version(), 300u);
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
  EXPECT_EQ(store.version(), 0u);
  // The working copy went back too: the next change starts from generation 0.
  const std::size_t objects = store.modify([](Environment& env) { return env.objects().size(); });
  EXPECT_EQ(objects, static_cast<std::size_t>(kObjects));
  EXPECT_EQ(generation_of(*store.snapshot()), 0);
  EXPECT_EQ(store.snapshot()->find_object("half"), nullptr);
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
