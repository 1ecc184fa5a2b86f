// Environment benchmark, its second unit: the self filter on the table scene and the shared
// snapshots of a changing map (environment_bench.h; main is in bench_environment.cpp).
#include <fcl/fcl.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <deque>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <tuple>

#include "bench_util.h"
#include "environment_bench.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/world/environment_store.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "fcl_oracle.h"
#include "robot_data.h"

namespace bvh_collision::environment_bench {
namespace {

using bench::Spread;
using bench::Table;

}  // namespace

// Occupied leaves that meet the robot (centre within half the cube's diagonal of a link).
int voxels_on_robot(const Octree& tree, const std::vector<Bvh<Obb>>& meshes, const std::vector<Transform>& poses) {
  int n = 0;
  for (const Octree::Leaf& leaf : tree.leaves()) {
    if (!tree.occupied(leaf.log_odds)) continue;
    const double size = tree.cube_size(leaf.depth), reach = 0.5 * std::sqrt(3.0) * size;
    const Vec3 centre = tree.cube_min(leaf.key) + Vec3::Constant(0.5 * size);
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      if (point_distance(meshes[m], poses[m], centre, reach).distance <= reach) {
        ++n;
        break;
      }
    }
  }
  return n;
}

// The self filter on the table scene with panda in it, reaching over the table: the camera sees
// the robot, and the filter keeps its points and shadows out of the octree. Timed: the filter
// alone, and filter plus insertion against inserting the raw scan; counted: points removed,
// voxels left on the robot, and whether the robot collides with the octree it built.
void self_filter(const Vec3& camera, double resolution, double padding, const Sizes& sizes, const std::string& dir) {
  const CollisionChecker checker = test::load_checker("panda");
  CheckerOptions with_proxies;
  with_proxies.proxy_levels = {0.02};
  const CollisionChecker proxied = test::load_checker("panda", with_proxies);
  std::vector<double> state(checker.model().variable_count(), 0.0);
  const std::map<std::string, double> reach_over_table = {
      {"panda_joint2", 0.3}, {"panda_joint4", -1.9}, {"panda_joint6", 2.2}, {"panda_joint7", 0.785}};
  for (std::size_t i = 0; i < state.size(); ++i) {
    const auto it = reach_over_table.find(checker.model().variable_names()[i]);
    if (it != reach_over_table.end()) state[i] = it->second;
  }
  std::vector<Transform> link_poses, poses;
  forward_kinematics(checker.model(), state.data(), link_poses);
  std::vector<Bvh<Obb>> meshes;
  for (std::size_t l = 0; l < link_poses.size(); ++l) {
    for (const CollisionElement& e : checker.model().links()[l].collision) {
      meshes.push_back(Bvh<Obb>::build(*e.mesh));
      poses.push_back(link_poses[l] * e.origin);
    }
  }
  const auto scan = table_scene(
      camera,
      [&](const Vec3& origin, const Vec3& direction, double best) {
        for (std::size_t m = 0; m < meshes.size(); ++m) {
          const RayHit hit = raycast(meshes[m], poses[m], origin, direction, std::min(best, 10.0));
          if (hit.hit) best = std::min(best, hit.distance);
        }
        return best;
      },
      sizes.width, sizes.height);
  const ScanPoint sensor = camera.cast<float>();
  std::vector<double> filter_s, filtered_insert_s, raw_insert_s, proxied_s;
  FilteredScan filtered, proxied_filtered;
  Octree raw(resolution), clean(resolution);
  for (std::size_t r = 0; r < sizes.runs; ++r) {
    raw = Octree(resolution);
    clean = Octree(resolution);
    filter_s.push_back(bench::time_us([&] { filtered = checker.filter_scan(state.data(), scan, sensor, padding); }) * 1e-6);
    filtered_insert_s.push_back(filter_s.back() + bench::time_us([&] {
      insert_scan(clean, filtered.obstacles, filtered.clear_only, sensor);
    }) * 1e-6);
    raw_insert_s.push_back(bench::time_us([&] { insert_scan(raw, scan, sensor); }) * 1e-6);
    proxied_s.push_back(bench::time_us([&] { proxied_filtered = proxied.filter_scan(state.data(), scan, sensor, padding); }) * 1e-6);
  }
  // The proxies only settle points sooner: the same points must come out.
  const bool same = proxied_filtered.on_robot == filtered.on_robot && proxied_filtered.shadowed == filtered.shadowed &&
                    proxied_filtered.obstacles.size() == filtered.obstacles.size();
  const int raw_on = voxels_on_robot(raw, meshes, poses), clean_on = voxels_on_robot(clean, meshes, poses);
  Environment raw_env(resolution), clean_env(resolution);
  raw_env.octree() = raw;
  clean_env.octree() = clean;
  EnvironmentRequest all;
  all.all_links = true;
  const auto raw_hit = checker.check_environment(state.data(), raw_env, all);
  const auto clean_hit = checker.check_environment(state.data(), clean_env, all);
  const double f = bench::median(filter_s), fi = bench::median(filtered_insert_s), ri = bench::median(raw_insert_s);
  const double points = static_cast<double>(scan.size());
  Table table("env_self_filter", "Self filter: panda reaching over the table, seen by the camera",
              {"step", "s", "Mpoints/s", "points on the robot", "points shadowed", "occupied voxels on the robot",
               "links colliding with the octree"});
  table.row({"raw insertion (no filter)", ri, points / ri * 1e-6, 0.0, 0.0, static_cast<double>(raw_on),
             static_cast<double>(raw_hit.contacts.size())});
  table.row({"self filter alone", f, points / f * 1e-6, static_cast<double>(filtered.on_robot),
             static_cast<double>(filtered.shadowed), std::nan(""), std::nan("")});
  const double pf = bench::median(proxied_s);
  table.row({same ? "self filter alone, 20 mm proxies (same points)" : "self filter alone, 20 mm proxies (POINTS DIFFER)", pf,
             points / pf * 1e-6, static_cast<double>(proxied_filtered.on_robot), static_cast<double>(proxied_filtered.shadowed),
             std::nan(""), std::nan("")});
  table.row({"self filter + insertion", fi, points / fi * 1e-6, static_cast<double>(filtered.on_robot),
             static_cast<double>(filtered.shadowed), static_cast<double>(clean_on), static_cast<double>(clean_hit.contacts.size())});
  table.note("Resolution " + bench::format(resolution) + " m, padding " + bench::format(padding) + " m; medians of " +
             std::to_string(sizes.runs) + " runs.");
  table.write(dir);
}

// --- Shared snapshots (issue 19): what a change copies, what snapshots held by readers cost ---

// Rolling ground of side `cells` voxels (2 cm): one occupied voxel per column, a map of about
// cells^2 occupied voxels (1M at 1000).
std::vector<ScanPoint> rolling_ground(int cells, double res) {
  std::vector<ScanPoint> out;
  out.reserve(std::size_t(cells) * cells);
  for (int i = 0; i < cells; ++i) {
    for (int j = 0; j < cells; ++j) {
      const double x = (i + 0.5) * res - 0.5 * cells * res, y = (j + 0.5) * res - 0.5 * cells * res;
      out.emplace_back(float(x), float(y), float(0.3 * std::sin(0.7 * x) * std::cos(0.5 * y)));
    }
  }
  return out;
}

// A downward camera at `eye`: rays to the ground below it (a 1.6 x 1.2 m patch), 1 cm noise.
std::vector<ScanPoint> ground_cloud(const Vec3& eye, int points, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<ScanPoint> out;
  for (int k = 0; k < points; ++k) {
    const double x = eye.x() + 0.8 * u(rng), y = eye.y() + 0.6 * u(rng);
    out.emplace_back(float(x), float(y), float(0.3 * std::sin(0.7 * x) * std::cos(0.5 * y) + noise(rng)));
  }
  return out;
}

void snapshot_table(const Sizes& sizes, const std::string& dir) {
  Table table("env_snapshots", "Shared snapshots: what a change copies, what readers' snapshots hold (2 cm map)",
              {"occupied voxels", "map MiB", "clear_box of one voxel, published: us (median)", "p99 us",
               "OctoMap copy of the map: us (a snapshot by copying)", "cloud points", "cloud insert + publish: ms (median)",
               "5 snapshots held / one map: median", "max", "OctoMap MiB"});
  const double res = 0.02;
  const int cells = sizes.runs > 1 ? 1000 : 200;
  Environment initial(res);
  insert_points(initial.octree(), rolling_ground(cells, res));
  const std::size_t occupied = occupied_voxels(initial.octree());
  octomap::OcTree reference(res);
  to_octomap(initial.octree(), reference);
  std::vector<double> copy_us;
  for (int r = 0; r < 5; ++r) copy_us.push_back(bench::time_us([&] { octomap::OcTree copy(reference); }));
  EnvironmentStore store(std::move(initial));

  // One voxel cleared at a time, each through the store (the copy-on-write and the publication),
  // while the snapshot before it is still held (as a reader's would be).
  std::mt19937_64 rng(11);
  const auto leaves = store.snapshot()->octree().leaves();
  std::vector<double> clear_us;
  for (int k = 0; k < 200; ++k) {
    const Octree::Leaf& l = leaves[rng() % leaves.size()];
    const Vec3 c = store.snapshot()->octree().cube_min(l.key) + Vec3::Constant(0.5 * res);
    const auto held = store.snapshot();
    clear_us.push_back(bench::time_us([&] { store.modify([&](Environment& env) { env.octree().clear_box(c, c); }); }));
  }

  // Clouds at 10 Hz from a camera moving 10 cm a cloud (1 m/s); four readers each hold one of
  // the four snapshots before the newest (a query that started up to 0.4 s ago).
  const int clouds = sizes.runs > 1 ? 100 : 20, points = 12000;
  std::deque<std::shared_ptr<const Environment>> held;
  std::vector<double> insert_ms, ratio;
  for (int c = 0; c < clouds; ++c) {
    const Vec3 eye(-3.0 + 0.1 * c, 0.2 * std::sin(0.3 * c), 1.5);
    const std::vector<ScanPoint> cloud = ground_cloud(eye, points, rng);
    insert_ms.push_back(bench::time_us([&] {
      store.modify([&](Environment& env) { insert_scan(env.octree(), cloud, ScanPoint(float(eye.x()), float(eye.y()), float(eye.z()))); });
    }) / 1000.0);
    held.push_back(store.snapshot());
    if (held.size() > 5) held.pop_front();
    std::vector<const Octree*> trees;
    for (const auto& e : held) trees.push_back(&e->octree());
    if (held.size() == 5) ratio.push_back(double(Octree::distinct_memory_bytes(trees)) / double(held.back()->octree().memory_bytes()));
  }
  table.row({double(occupied), store.snapshot()->octree().memory_bytes() / 1048576.0, bench::median(clear_us),
             bench::percentile(clear_us, 0.99), bench::median(copy_us), double(points), bench::median(insert_ms),
             bench::median(ratio), *std::max_element(ratio.begin(), ratio.end()), reference.memoryUsage() / 1048576.0});
  table.note("The octree's nodes sit in 6 KiB pages shared between copies; a change copies the pages it writes "
             "(octree.h). A map of rolling ground (one occupied voxel per 2 cm column). Clearing: 200 random voxels, "
             "each through EnvironmentStore::modify (copy on write, then the publication of a new snapshot) while the "
             "previous snapshot is held. Streaming: " + std::to_string(clouds) + " clouds of " + std::to_string(points) +
             " points (rays from a camera 1.5 m up, moving 10 cm a cloud); after each, the newest snapshot and the "
             "four before it are held, and the memory they hold together (shared pages once) is divided by one map's.");
  table.write(dir);
}

}  // namespace bvh_collision::environment_bench
