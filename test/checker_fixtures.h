// A CollisionChecker for the demo arm or one of the real robots of ../shared/robots, with the
// allowed-collision matrix from adjacency: what most checker tests and benchmarks start from.
#pragma once

#include <fstream>
#include <sstream>
#include <string>
#include <utility>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision::test {

// The package's own demo arm (urdf/demo_arm.urdf: primitives only, no mesh files).
inline RobotModel demo_arm_model() {
  return RobotModel::from_urdf(*load_robot_description_file(source_dir() + "/urdf/demo_arm.urdf"), PackageResolver({}));
}

// Options whose proxy levels and clearance grids come from the tests' cache (proxy_cache_dir)
// unless they name a cache of their own: a robot's levels and grids are then built once per
// `make test` (by the first program that asks), not once per program and again under the
// sanitizers (pr2's grids: 6 s of CPU in Release, a minute under them). What the builders make is
// tested uncached, on its own (test_link_proxy, test_pair_clearance's PairClearance::build); a
// checker with neither is left as it is, and so is a benchmark's (it times the build).
inline CheckerOptions with_test_proxy_cache(CheckerOptions options) {
#ifndef BVH_COLLISION_BENCHMARK
  const bool builds = !options.proxy_levels.empty() || options.pair_clearance_cells > 0;
  if (builds && options.proxy_cache.empty()) options.proxy_cache = proxy_cache_dir();
#endif
  return options;
}

inline CollisionChecker demo_arm_checker(const CheckerOptions& options = {}) {
  RobotModel model = demo_arm_model();
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  return CollisionChecker(std::move(model), std::move(acm), with_test_proxy_cache(options));
}

inline CollisionChecker load_checker(const std::string& robot, const CheckerOptions& options = {}) {
  const std::string dir = robots_dir() + "/" + robot;
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  return CollisionChecker(std::move(model), std::move(acm), with_test_proxy_cache(options));
}

// A robot of ../shared/robots as MoveIt sets it up: adjacent links and its SRDF's disabled pairs
// allowed.
inline CollisionChecker load_as_moveit(const std::string& robot, const CheckerOptions& options = {}) {
  const std::string dir = robots_dir() + "/" + robot;
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  std::ifstream srdf(dir + "/robot.srdf");
  std::stringstream text;
  text << srdf.rdbuf();
  apply_srdf(parse_srdf(text.str(), &model), model, acm);
  return CollisionChecker(std::move(model), std::move(acm), with_test_proxy_cache(options));
}

inline CollisionChecker panda_as_moveit(const CheckerOptions& options = {}) { return load_as_moveit("panda", options); }

// Panda as above with the node's proxy levels (5, 10, 20 mm), built once per test binary.
inline const CollisionChecker& panda_with_proxies() {
  static const CollisionChecker checker = [] {
    CheckerOptions options;
    options.proxy_levels = {0.005, 0.01, 0.02};
    options.proxy_cache = proxy_cache_dir();
    return panda_as_moveit(options);
  }();
  return checker;
}

}  // namespace bvh_collision::test
