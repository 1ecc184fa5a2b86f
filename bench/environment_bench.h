// What the environment benchmark's units share (bench_environment.cpp, the insertion, octree and
// clutter tables; bench_environment_world.cpp, the self filter and the snapshots;
// bench_environment_updates.cpp, the clearing and per-core insertion tables;
// bench_environment_motions.cpp, the motion table; bench_environment_live.cpp, the live world):
// the run's sizes (the scenes: bench_scenes.h).
#pragma once

#include <octomap/OcTree.h>

#include <cstddef>
#include <functional>
#include <map>
#include <tuple>
#include <string>
#include <vector>

#include "bvh_collision/octree/octree.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/octree/scan.h"
#include "bench_scenes.h"

namespace bvh_collision::environment_bench {

struct Sizes {
  std::size_t runs, states;
  int width, height;  // the camera's rays
  std::vector<double> resolutions;
  std::vector<int> clutter;  // box counts for the growth curve
  std::size_t motions;       // random motions of the motion table
  // The proxy levels of the tolerance tables: the node's three (5, 10, 20 mm); the quick run
  // builds the 20 mm level only (panda's 5 mm level is most of its time).
  std::vector<double> proxy_levels;
};

std::size_t occupied_voxels(const Octree& tree);
// Every leaf by (key of its lowest voxel, depth) with its log-odds: two trees are identical when
// these are equal.
using LeafMap = std::map<std::tuple<int, int, int, int>, float>;
LeafMap leaves_of(const Octree& tree);
LeafMap leaves_of(const octomap::OcTree& tree);

// The self filter on the table scene with panda reaching over the table, and the shared
// snapshots of a changing map (bench_environment_world.cpp).
void self_filter(const Vec3& camera, double resolution, double padding, const Sizes& sizes, const std::string& dir);
void snapshot_table(const Sizes& sizes, const std::string& dir);
// How long an obstacle that left stays in the map, by sensor model, and what faster clearing
// costs a thin or dark obstacle (bench_environment_updates.cpp).
void clearing_table(bool quick, const std::string& dir);
// Insertion against OctoMap per core (CPU time) on a room's depth image and a LiDAR scan, at 2 and
// 5 cm, trees compared (bench_environment_updates.cpp).
void insertion_cpu_table(bool quick, const std::string& dir);
// Motions against tolerance on the demo arm and its pillar (bench_environment_motions.cpp).
void motion_table(const Sizes& sizes, const std::string& dir);
// The demo's arm (its pillar: bench_scenes.h).
CollisionChecker demo_checker(const std::vector<double>& proxy_levels);
// bench_environment_live.cpp: certified motions while clouds arrive (table live_world).
void live_world_table(const Sizes& sizes, const std::string& dir);
// "5, 10 and 20 mm": the proxy levels a table was measured with.
std::string levels_mm(const std::vector<double>& levels);

}  // namespace bvh_collision::environment_bench
