// The service requests' fuzz corpus (test/fuzz/corpus/service_request: the seeds of
// scripts/make_loader_corpus.py and every input `make fuzz` found) replayed into a node on the
// demo arm, in this process, under rostest's master: each request is refused by name or
// answered, none takes the node down, and the node answers a plain check afterwards.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "fuzz/message_targets.h"

namespace bvh_collision {
namespace {

namespace fs = std::filesystem;

TEST(FuzzReplay, ServiceRequests) {
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(fs::path(BVH_COLLISION_FUZZ_CORPUS) / "service_request")) {
    files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  double slowest = 0.0;
  for (const fs::path& file : files) {
    if (std::getenv("BVH_COLLISION_REPLAY_VERBOSE")) std::fprintf(stderr, "%s\n", file.filename().c_str());
    std::ifstream in(file, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto start = std::chrono::steady_clock::now();
    EXPECT_EQ(fuzz::check_service_request(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()), "")
        << file.filename();
    slowest = std::max(slowest, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  EXPECT_GE(files.size(), 40u);  // the seeds: every service, each with its bad fields
  // A hang would show here: a deadline, ten times the slowest input under the sanitizers
  // (a certified motion at its 20,000-state cap, about 10 s there; 0.3 s in Release).
  EXPECT_LT(slowest, 120.0);
  std::printf("service_request: %zu inputs, slowest %.3f s\n", files.size(), slowest);
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();  // the target starts ROS itself (ros::init, its own node names)
}
