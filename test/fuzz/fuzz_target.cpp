// libFuzzer's entry point for one loader target (chosen at compile time, see CMakeLists.txt's
// fuzz section): a violated invariant aborts, which libFuzzer records as a crash with its input.
#include <cstdio>
#include <cstdlib>

#include "loader_targets.h"
#include "message_targets.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string problem = bvh_collision::fuzz::BVH_COLLISION_FUZZ_TARGET(data, size);
  if (!problem.empty()) {
    std::fprintf(stderr, "invariant violated: %s\n", problem.c_str());
    std::abort();
  }
  return 0;
}
