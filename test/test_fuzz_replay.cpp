// The fuzz corpora replayed (test/fuzz/corpus: the mutation sweep of malformed robot
// descriptions, meshes, SRDFs, OctoMap files and point clouds written by
// scripts/make_loader_corpus.py, plus every input
// `make fuzz` found). Each input must be refused by name or load into something valid (see
// test/fuzz/loader_targets.h), none may hang, and the whole replay stays far below 1 GiB.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "fuzz/loader_targets.h"
#include "fuzz/message_targets.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

namespace fs = std::filesystem;
using Target = std::string (*)(const std::uint8_t*, std::size_t);

// Replays one corpus folder; returns the number of inputs.
std::size_t replay(const std::string& name, Target target) {
  const fs::path folder = fs::path(BVH_COLLISION_FUZZ_CORPUS) / name;
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  double slowest = 0.0;
  std::string slowest_file;
  for (const fs::path& file : files) {
    // A crash ends the process: BVH_COLLISION_REPLAY_VERBOSE=1 names each input first.
    if (std::getenv("BVH_COLLISION_REPLAY_VERBOSE")) std::fprintf(stderr, "%s\n", file.c_str());
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto start = std::chrono::steady_clock::now();
    const std::string problem = target(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(problem, "") << file.filename();
    if (seconds > slowest) slowest = seconds, slowest_file = file.filename();
  }
  // A hang would show here. A deadline, not a speed claim: the slowest input (a 16k-point cloud)
  // takes about 2 s in Release and 10 s under the sanitizers (docs/testing.md); ten times that.
  EXPECT_LT(slowest, 120.0) << slowest_file;
  std::printf("%s: %zu inputs, slowest %.3f s (%s)\n", name.c_str(), files.size(), slowest, slowest_file.c_str());
  return files.size();
}

// The seed corpora are the mutation sweep: they must all be there (an empty folder
// would pass vacuously).
TEST(FuzzReplay, RobotDescriptions) { EXPECT_GE(replay("robot_description", fuzz::check_robot_description), 250u); }
TEST(FuzzReplay, Meshes) { EXPECT_GE(replay("mesh", fuzz::check_mesh), 120u); }
TEST(FuzzReplay, Srdf) { EXPECT_GE(replay("srdf", fuzz::check_srdf), 20u); }
TEST(FuzzReplay, OctreeFiles) { EXPECT_GE(replay("octree_file", fuzz::check_octree_file), 30u); }
TEST(FuzzReplay, SceneFiles) { EXPECT_GE(replay("scene_file", fuzz::check_scene_file), 30u); }
TEST(FuzzReplay, PointClouds) { EXPECT_GE(replay("point_cloud", fuzz::check_point_cloud), 20u); }

// Run last (gtest keeps declaration order): the whole replay's peak memory.
TEST(FuzzReplay, PeakMemoryStaysFarBelowOneGigabyte) {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  EXPECT_LT(usage.ru_maxrss, 1L << 20) << "kB";  // ru_maxrss is in kB: 1 GiB
  std::printf("peak resident memory: %ld MiB\n", usage.ru_maxrss >> 10);
}

}  // namespace
}  // namespace bvh_collision
