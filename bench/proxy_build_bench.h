// The proxy build section of the report (bench/bench_proxy_build.cpp), run by bench_self_collision.
#pragma once

#include <string>

namespace bvh_collision {
namespace bench {

// Writes the table proxy_build to `dir` (and prints it): every link's proxy at 5, 10 and 20 mm for
// panda, ur5e, pr2, a generated two-arm robot and a 30 cm attached box (quick: 20 mm, no ur5e or pr2).
void proxy_build_section(const std::string& dir, bool quick);

}  // namespace bench
}  // namespace bvh_collision
