// Where tests find the real robots of ../shared/robots (docs/design.md).
// BVH_COLLISION_ROBOTS overrides the default folder beside the repository. When the folder is
// missing a test is skipped with a message, except under CI=true, where that is a failure.
#pragma once

#include <dlfcn.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

namespace bvh_collision::test {

inline std::string robots_dir() {
  const char* env = std::getenv("BVH_COLLISION_ROBOTS");
  return (env != nullptr && *env != '\0') ? std::string(env) : std::string(BVH_COLLISION_DEFAULT_ROBOTS);
}

inline bool running_in_ci() {
  const char* ci = std::getenv("CI");
  return ci != nullptr && std::string(ci) == "true";
}

inline std::string source_dir() { return BVH_COLLISION_SOURCE_DIR; }

// A folder where tests keep the robots' link proxies by content (narrowphase/link_proxy_cache.h),
// shared by the test programs of one build and by the sanitizer pass that runs them again: panda's
// proxy levels are built once per `make test`, not once per program (writes are atomic). Their
// build is tested on its own, uncached (test_link_proxy).
inline std::string proxy_cache_dir() {
#ifdef BVH_COLLISION_TEST_PROXY_CACHE
  return BVH_COLLISION_TEST_PROXY_CACHE;
#else
  return (std::filesystem::temp_directory_path() / "bvh_collision_test_proxy_cache").string();
#endif
}

// Whether AddressSanitizer's runtime is in the process: the sanitizer pass of `make test` runs
// the Release test programs on the sanitized library (scripts/run_tests.sh), so this is decided
// when the test runs, not when it is compiled.
inline bool sanitized() {
  static const bool loaded = dlsym(RTLD_DEFAULT, "__asan_init") != nullptr;
  return loaded;
}

// Cases for a randomized test: all of them in the Release build, a quarter under the sanitizers
// (ten to forty times slower), which look for memory errors, not for rarer geometry.
inline int sized(int cases) { return sanitized() ? std::max(1, cases / 4) : cases; }

}  // namespace bvh_collision::test

// Use at the top of a test body that needs ../shared/robots.
#define BVH_REQUIRE_ROBOTS()                                                                   \
  do {                                                                                         \
    const std::string dir_ = ::bvh_collision::test::robots_dir();                               \
    if (!std::filesystem::is_directory(dir_)) {                                                \
      if (::bvh_collision::test::running_in_ci()) {                                            \
        FAIL() << "robots folder '" << dir_ << "' is missing (CI=true: this is a failure)";    \
      }                                                                                        \
      GTEST_SKIP() << "robots folder '" << dir_ << "' is missing; set BVH_COLLISION_ROBOTS";   \
    }                                                                                          \
  } while (false)
