// Environment benchmark, section 4 and part of 5 of the report (make bench): scan insertion
// against octomap::OcTree::insertPointCloud (identical trees required); the robot against the
// octree against FCL's OcTree collision (same voxels, same states, answers compared); how time
// and memory grow with occupied voxels and resolution; the voxelisation error against a known
// surface; what workspace bounds save; and the self filter.
// Usage: bench_environment [OUTPUT_DIR] [--quick]
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

namespace bvh_collision {

// The shared scene and sizes (environment_bench.h), defined here for both units.
namespace environment_bench {

std::size_t occupied_voxels(const Octree& tree) {
  std::size_t n = 0;
  for (const Octree::Leaf& l : tree.leaves()) n += tree.occupied(l.log_odds);
  return n;
}

LeafMap leaves_of(const Octree& tree) {
  LeafMap m;
  for (const auto& l : tree.leaves()) m[{l.key.k[0], l.key.k[1], l.key.k[2], l.depth}] = l.log_odds;
  return m;
}
LeafMap leaves_of(const octomap::OcTree& tree) {
  LeafMap m;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    const int depth = static_cast<int>(it.getDepth());
    const int low = ~((1 << (16 - depth)) - 1);
    const auto k = it.getKey();
    m[{k[0] & low, k[1] & low, k[2] & low, depth}] = it->getLogOdds();
  }
  return m;
}

std::string levels_mm(const std::vector<double>& levels) {
  std::string text;
  for (std::size_t i = 0; i < levels.size(); ++i) {
    text += (i == 0 ? "" : i + 1 == levels.size() ? " and " : ", ") + bench::format(levels[i] * 1000);
  }
  return text + " mm";
}

}  // namespace environment_bench

namespace {

using namespace environment_bench;



using bench::Spread;
using bench::Table;


// The robot's links as FCL objects (OBBRSS models of the same meshes) and FCL's octree of the
// same voxels, for robot-against-octree collision as FCL computes it.
struct FclScene {
  std::vector<std::shared_ptr<fcl::CollisionObjectd>> objects;
  std::vector<int> link;
  std::vector<Transform> origin;
  std::shared_ptr<octomap::OcTree> octree;
  std::unique_ptr<fcl::CollisionObjectd> octree_object;

  FclScene(const CollisionChecker& checker, const Octree& tree) : octree(std::make_shared<octomap::OcTree>(tree.resolution())) {
    for (std::size_t l = 0; l < checker.model().links().size(); ++l) {
      for (const CollisionElement& e : checker.model().links()[l].collision) {
        objects.push_back(std::make_shared<fcl::CollisionObjectd>(test::fcl_model<fcl::OBBRSSd>(*e.mesh)));
        link.push_back(static_cast<int>(l));
        origin.push_back(e.origin);
      }
    }
    to_octomap(tree, *octree);
    octree_object = std::make_unique<fcl::CollisionObjectd>(std::make_shared<fcl::OcTreed>(octree));
    octree_object->computeAABB();
  }

  bool collides(const RobotModel& model, const double* state) {
    thread_local std::vector<Transform> poses;
    forward_kinematics(model, state, poses);
    for (std::size_t k = 0; k < objects.size(); ++k) {
      objects[k]->setTransform(test::fcl_transform(poses[link[k]] * origin[k]));
      objects[k]->computeAABB();
      fcl::CollisionRequestd r;
      fcl::CollisionResultd result;
      if (fcl::collide(objects[k].get(), octree_object.get(), r, result) > 0) return true;
    }
    return false;
  }
};

std::vector<std::vector<double>> random_states(const RobotModel& m, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(random_configuration(m, rng));
  return out;
}

// Robot against the octree, ours (surfaces, FCL's semantics; and the default, solids; and
// distance) and FCL's, microseconds per state as medians of runs; answers compared.
struct CheckTimes {
  Spread ours, fcl, solids, distance;
  std::size_t colliding = 0, disagreements = 0;
};

CheckTimes time_checks(const CollisionChecker& checker, const Environment& env, const std::vector<std::vector<double>>& states,
                       std::size_t runs) {
  FclScene fcl_scene(checker, env.octree());
  EnvironmentRequest surfaces;
  surfaces.objects = false;
  surfaces.solids = false;
  EnvironmentRequest solids = surfaces, distance = surfaces;
  solids.solids = true;
  distance.distance = true;
  const std::size_t n = states.size();
  std::vector<char> ours(n), theirs(n);
  std::vector<double> t_ours, t_fcl, t_solids, t_distance;
  for (std::size_t r = 0; r < runs; ++r) {
    t_ours.push_back(bench::us_per_item(n, [&] {
      for (std::size_t i = 0; i < n; ++i) ours[i] = checker.check_environment(states[i].data(), env, surfaces).collision;
    }));
    t_fcl.push_back(bench::us_per_item(n, [&] {
      for (std::size_t i = 0; i < n; ++i) theirs[i] = fcl_scene.collides(checker.model(), states[i].data());
    }));
    t_solids.push_back(bench::us_per_item(n, [&] {
      for (std::size_t i = 0; i < n; ++i) checker.check_environment(states[i].data(), env, solids);
    }));
    t_distance.push_back(bench::us_per_item(n, [&] {
      for (std::size_t i = 0; i < n; ++i) checker.check_environment(states[i].data(), env, distance);
    }));
  }
  CheckTimes out{bench::spread(t_ours), bench::spread(t_fcl), bench::spread(t_solids), bench::spread(t_distance)};
  for (std::size_t i = 0; i < n; ++i) {
    out.colliding += ours[i];
    out.disagreements += ours[i] != theirs[i];
  }
  return out;
}


// Every k-th point of the scan (a smaller cloud from the same camera).
std::vector<ScanPoint> every(const std::vector<ScanPoint>& scan, std::size_t k) {
  std::vector<ScanPoint> out;
  for (std::size_t i = 0; i < scan.size(); i += k) out.push_back(scan[i]);
  return out;
}

void insertion_table(const std::vector<ScanPoint>& scan, const Vec3& camera, const Sizes& sizes, const std::string& dir) {
  Table table("env_insert", "Scan insertion against octomap::OcTree::insertPointCloud",
              {"resolution m", "points", "ours s", "ours min", "ours max", "OctoMap s", "OctoMap min", "OctoMap max",
               "ours Mpoints/s", "OctoMap Mpoints/s", "OctoMap / ours", "ours one core s", "identical trees"});
  const octomap::point3d origin(camera.x(), camera.y(), camera.z());
  ScanOptions one_core;
  one_core.threads = 1;
  for (const double res : sizes.resolutions) {
    for (const std::size_t k : {9, 3, 1}) {
      const std::vector<ScanPoint> cloud = every(scan, k);
      octomap::Pointcloud reference_cloud;
      for (const ScanPoint& p : cloud) reference_cloud.push_back(p.x(), p.y(), p.z());
      std::vector<double> ours, theirs, single;
      bool same = true;
      for (std::size_t r = 0; r < sizes.runs; ++r) {
        Octree tree(res), tree1(res);
        octomap::OcTree reference(res);
        ours.push_back(1e-6 * bench::time_us([&] { insert_scan(tree, cloud, camera.cast<float>()); }));
        single.push_back(1e-6 * bench::time_us([&] { insert_scan(tree1, cloud, camera.cast<float>(), one_core); }));
        theirs.push_back(1e-6 * bench::time_us([&] { reference.insertPointCloud(reference_cloud, origin); }));
        if (r == 0) same = leaves_of(tree) == leaves_of(reference);
      }
      const Spread a = bench::spread(ours), b = bench::spread(theirs);
      const double points = static_cast<double>(cloud.size());
      table.row({res, points, a.median, a.low, a.high, b.median, b.low, b.high, 1e-6 * points / a.median,
                 1e-6 * points / b.median, b.median / a.median, bench::median(single), same ? "yes" : "NO"});
    }
  }
  table.note("A depth camera's view of a table scene (every 9th, 3rd and every point); ours on every core unless said; "
             "medians of " + std::to_string(sizes.runs) + " runs. 'identical trees': every leaf, depth and log-odds value "
             "equal to OctoMap's.");
  table.write(dir);
}

void resolution_table(const std::vector<ScanPoint>& scan, const Vec3& camera, const CollisionChecker& checker,
                      const std::vector<std::vector<double>>& states, const Sizes& sizes, const std::string& dir) {
  Table table("env_resolution", "Robot against the octree, by resolution (table scene, panda)",
              {"resolution m", "occupied voxels", "octree nodes", "memory KiB", "OctoMap memory KiB", "ours us/state",
               "min", "max", "FCL us/state", "min", "max", "FCL / ours", "ours solids us/state", "ours distance us/state",
               "colliding states", "disagreements with FCL"});
  std::vector<double> resolutions = sizes.resolutions;
  resolutions.insert(resolutions.begin(), resolutions.front() / 2);
  resolutions.push_back(resolutions.back() * 2);
  for (const double res : resolutions) {
    Environment env(res);
    insert_scan(env.octree(), scan, camera.cast<float>());
    octomap::OcTree reference(res);
    to_octomap(env.octree(), reference);
    const CheckTimes t = time_checks(checker, env, states, sizes.runs);
    table.row({res, static_cast<double>(occupied_voxels(env.octree())), static_cast<double>(env.octree().node_count()),
               env.octree().memory_bytes() / 1024.0, reference.memoryUsage() / 1024.0, t.ours.median, t.ours.low,
               t.ours.high, t.fcl.median, t.fcl.low, t.fcl.high, t.fcl.median / t.ours.median, t.solids.median,
               t.distance.median, static_cast<double>(t.colliding), static_cast<double>(t.disagreements)});
  }
  table.note(std::to_string(states.size()) + " uniform random panda states; boolean checks as surfaces (FCL's semantics) "
             "unless 'solids' (the default: occupied cubes inside closed links count); medians of " +
             std::to_string(sizes.runs) + " runs.");
  table.write(dir);
}

// The speed-against-error curve of panda against the 2 cm table-scene octree (report section 1,
// the `octree` rows of speed_error.json; scripts/bench_report.py merges them in): boolean checks,
// solids, at tolerances 0-20 mm, one state at a time and as one batch, against the exact answer.
// At a tolerance the link proxies answer against the octree's distance field (kept, as the node
// keeps it), at tolerance 0 the exact OBB trees.
void speed_error_octree_table(const std::vector<ScanPoint>& scan, const Vec3& camera, const CollisionChecker& checker,
                              const std::vector<std::vector<double>>& states, const Sizes& sizes, const std::string& dir) {
  Table table("speed_error_octree", "Panda against the table-scene octree (2 cm): time per state against tolerance",
              {"robot", "scene", "tolerance_mm", "mode", "us_per_state", "us_per_state min", "us_per_state max", "false_positive_pct", "false_negatives",
               "farthest_false_positive_mm", "fcl_exact_us_per_state", "proxy_level_mm", "proxy_leaves",
               "proxy_build_s"});
  Environment env(0.02);
  insert_scan(env.octree(), scan, camera.cast<float>());
  const CheckTimes exact = time_checks(checker, env, states, sizes.runs);
  const std::size_t n = states.size();
  std::vector<double> distance(n), flat;
  EnvironmentRequest truth;
  truth.distance = true;
  for (std::size_t i = 0; i < n; ++i) {
    const EnvironmentResult r = checker.check_environment(states[i].data(), env, truth);
    distance[i] = r.collision ? 0.0 : r.min_distance;
    flat.insert(flat.end(), states[i].begin(), states[i].end());
  }
  // Every row runs with the octree's distance field kept, as the node keeps one (it builds it
  // after each cloud); its build is timed once here.
  const double field_ms = 1e-3 * bench::time_us([&] { checker.prepare_distance_field(env); });
  for (const double mm : {0.0, 2.0, 5.0, 10.0, 20.0}) {
    EnvironmentRequest one;
    one.tolerance = mm * 1e-3;
    BatchRequest batch;
    batch.self = false;
    batch.tolerance = one.tolerance;
    std::vector<char> single(n), many;
    std::vector<double> t_single, t_batch;
    for (std::size_t r = 0; r < sizes.runs; ++r) {
      t_single.push_back(bench::us_per_item(n, [&] {
        for (std::size_t i = 0; i < n; ++i) single[i] = checker.check_environment(states[i].data(), env, one).collision;
      }));
      t_batch.push_back(bench::us_per_item(n, [&] { many = checker.check_batch(flat.data(), n, &env, batch); }));
    }
    for (const auto& [mode, hits, times] : {std::tuple{"single", &single, &t_single}, std::tuple{"batch", &many, &t_batch}}) {
      const bench::AnswerErrors e = bench::answer_errors(*hits, distance);
      // The level an environment check at this tolerance answers from (up to twice it).
      const ProxyLevel* level = checker.accelerators().proxies_for(2.0 * one.tolerance);
      const Spread time = bench::spread(*times);
      table.row({"panda", "octree", mm, mode, time.median, time.low, time.high, 100.0 * e.false_positives / n,
                 static_cast<double>(e.false_negatives), e.farthest_false_positive * 1000, exact.fcl.median,
                 level ? level->level * 1000 : 0.0, level ? double(level->leaves) : 0.0, level ? level->build_seconds : 0.0});
    }
  }
  table.note(std::to_string(n) + " uniform random panda states, solids, adjacent-link matrix, proxy levels " +
             levels_mm(sizes.proxy_levels) + "; the truth is our exact distance to the octree. Every row with the octree's distance field kept "
             "(octree/distance_field.h, built once in " + bench::format(field_ms) + " ms, as the node does after each "
             "cloud): links whose bounding sphere it clears skip the octree, and at a tolerance t the other links' "
             "proxies of the coarsest level up to 2 t answer against the field and its occupancy grid. single: one "
             "check_environment per state; batch: check_batch with self off on the shared thread pool. FCL: exact, "
             "surfaces, one state at a time.");
  table.write(dir);
}

// Random boxes (2 to 8 cm) in an 8 x 8 x 2 m room around the robot (none on its base), their
// surfaces sampled at a quarter voxel.
std::vector<ScanPoint> clutter(int boxes, double resolution, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<ScanPoint> points;
  const double step = resolution / 4;
  for (int b = 0; b < boxes; ++b) {
    const Vec3 lo(-4.0 + 8.0 * u(rng), -4.0 + 8.0 * u(rng), 2.0 * u(rng));
    const Vec3 size = Vec3::Constant(0.02) + 0.06 * Vec3(u(rng), u(rng), u(rng));
    if (lo.head<2>().norm() < 0.3) continue;  // not on the robot's base
    for (int axis = 0; axis < 3; ++axis) {
      const int i = (axis + 1) % 3, j = (axis + 2) % 3;
      for (double s = 0; s <= size[i]; s += step) {
        for (double t = 0; t <= size[j]; t += step) {
          for (const double side : {0.0, size[axis]}) {
            Vec3 p = lo;
            p[axis] += side, p[i] += s, p[j] += t;
            points.push_back(p.cast<float>());
          }
        }
      }
    }
  }
  return points;
}

void clutter_table(const CollisionChecker& checker, const std::vector<std::vector<double>>& states, const Sizes& sizes,
                   const std::string& dir) {
  Table table("env_clutter", "Growth with the number of occupied voxels (random boxes in a room around panda, 2 cm)",
              {"boxes", "occupied voxels", "octree nodes", "memory KiB", "OctoMap memory KiB", "free states",
               "ours us/free state", "min", "max", "FCL us/free state", "min", "max", "FCL / ours",
               "ours us/state (all states)", "FCL us/state (all states)", "ours distance us/state",
               "disagreements with FCL"});
  const double res = 0.02;
  for (const int boxes : sizes.clutter) {
    std::mt19937_64 rng(3);
    Environment env(res);
    insert_points(env.octree(), clutter(boxes, res, rng));
    octomap::OcTree reference(res);
    to_octomap(env.octree(), reference);
    const CheckTimes all = time_checks(checker, env, states, sizes.runs);
    // Proving a state free is what grows with the voxels (a colliding state stops at its first
    // contact): the curve is the time over the states free in this scene.
    EnvironmentRequest surfaces;
    surfaces.objects = surfaces.solids = false;
    std::vector<std::vector<double>> free_states;
    for (const auto& s : states) {
      if (!checker.check_environment(s.data(), env, surfaces).collision) free_states.push_back(s);
    }
    const double na = std::numeric_limits<double>::quiet_NaN();
    const CheckTimes free = free_states.empty() ? CheckTimes{} : time_checks(checker, env, free_states, sizes.runs);
    const auto value = [&](double x) { return free_states.empty() ? na : x; };
    table.row({static_cast<double>(boxes), static_cast<double>(occupied_voxels(env.octree())),
               static_cast<double>(env.octree().node_count()), env.octree().memory_bytes() / 1024.0,
               reference.memoryUsage() / 1024.0, static_cast<double>(free_states.size()), value(free.ours.median),
               value(free.ours.low), value(free.ours.high), value(free.fcl.median), value(free.fcl.low),
               value(free.fcl.high), value(free.fcl.median / free.ours.median), all.ours.median, all.fcl.median,
               all.distance.median, static_cast<double>(all.disagreements)});
  }
  table.note("Boxes of 2 to 8 cm placed at random in an 8 x 8 x 2 m room around panda (none on its base), their surfaces inserted as end points; the "
             "same " + std::to_string(states.size()) + " random states at every count, timed over the states free in "
             "that scene and over all of them; boolean checks as surfaces (FCL's semantics); medians of " +
             std::to_string(sizes.runs) + " runs.");
  table.write(dir);
}

// Fibonacci-spiral points on a sphere, at most `spacing` apart.
std::vector<ScanPoint> sphere_surface(const Vec3& centre, double radius, double spacing) {
  const int n = static_cast<int>(4 * M_PI * radius * radius / (spacing * spacing)) + 1;
  std::vector<ScanPoint> points;
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n, r = std::sqrt(1.0 - z * z);
    points.push_back((centre + radius * Vec3(r * std::cos(golden * i), r * std::sin(golden * i), z)).cast<float>());
  }
  return points;
}

// The voxelisation error: a sphere known exactly (a collision object) against its surface
// inserted into the octree; distances from panda's links to both, over states near it.
void voxel_error_table(const CollisionChecker& checker, const Sizes& sizes, const std::string& dir) {
  Table table("env_voxel_error", "Voxelisation error: distance to an octree of a sphere's surface against the sphere",
              {"resolution m", "voxel diagonal mm", "largest error mm", "mean error mm", "smallest error mm",
               "false collisions", "missed collisions", "ours us/state (octree distance)"});
  const Vec3 centre(0.45, 0.0, 0.45);
  const double radius = 0.15;
  Environment exact(0.1);
  exact.add_object("sphere", ObjectShape::sphere(radius), Transform::Translation(centre));
  EnvironmentRequest to_object, to_octree;
  to_object.distance = to_octree.distance = true;
  to_object.octree = false;
  to_octree.objects = false;
  // States whose true distance is within 20 cm (near it, where the error matters).
  std::mt19937_64 rng(17);
  std::vector<std::vector<double>> states;
  std::vector<double> truth;
  while (states.size() < sizes.states / 4) {
    const auto s = random_configuration(checker.model(), rng);
    const EnvironmentResult r = checker.check_environment(s.data(), exact, to_object);
    if (r.min_distance <= 0.2) states.push_back(s), truth.push_back(r.min_distance);
  }
  for (const double res : sizes.resolutions) {
    Environment env(res);
    insert_points(env.octree(), sphere_surface(centre, radius, res / 4));
    std::vector<double> errors, times;
    std::size_t false_hits = 0, missed = 0;
    for (std::size_t i = 0; i < states.size(); ++i) {
      EnvironmentResult r;
      times.push_back(bench::time_us([&] { r = checker.check_environment(states[i].data(), env, to_octree); }));
      errors.push_back(truth[i] - r.min_distance);
      false_hits += r.collision && truth[i] > 0;
      missed += !r.collision && truth[i] <= 0;
    }
    table.row({res, 1000 * std::sqrt(3.0) * res, 1000 * *std::max_element(errors.begin(), errors.end()),
               1000 * bench::mean(errors), 1000 * *std::min_element(errors.begin(), errors.end()),
               static_cast<double>(false_hits), static_cast<double>(missed), bench::median(times)});
  }
  table.note("A 15 cm sphere 45 cm in front of panda: its surface sampled at a quarter voxel and inserted; " +
             std::to_string(states.size()) + " random states within 20 cm of the true sphere. Error = true distance - "
             "distance to the occupied voxels: the voxels hold the surface, so the octree can only be nearer (error >= 0), "
             "by at most a voxel's diagonal. A false collision is a state that meets a voxel but not the sphere.");
  table.write(dir);
}

// "Model only what the scene needs": obstacles beyond the robot's reach are not inserted.
void workspace_table(const std::vector<ScanPoint>& scan, const Vec3& camera, const CollisionChecker& checker,
                     const std::vector<std::vector<double>>& states, const Sizes& sizes, const std::string& dir) {
  Table table("env_workspace", "Workspace bounds (the node's default: reach + 0.5 m around the base), table scene, 2 cm",
              {"setting", "points inserted", "insert s", "min", "max", "octree nodes", "memory KiB", "us/state (solids)",
               "saved per scan s", "saved per query us", "colliding states"});
  const float half = static_cast<float>(checker.reach() + 0.5);
  ScanOptions bounded;
  bounded.workspace = ScanWorkspace{ScanPoint::Constant(-half), ScanPoint::Constant(half)};
  double base_insert = 0, base_query = 0;
  for (const bool use : {false, true}) {
    const ScanOptions options = use ? bounded : ScanOptions{};
    std::vector<double> insert_s;
    Environment env(0.02);
    ScanStats stats;
    for (std::size_t r = 0; r < sizes.runs; ++r) {
      Octree tree(0.02);
      insert_s.push_back(1e-6 * bench::time_us([&] { stats = insert_scan(tree, scan, camera.cast<float>(), options); }));
      env.octree() = std::move(tree);
    }
    const CheckTimes t = time_checks(checker, env, states, sizes.runs);
    const Spread in = bench::spread(insert_s);
    if (!use) base_insert = in.median, base_query = t.solids.median;
    const double na = std::numeric_limits<double>::quiet_NaN();
    table.row({use ? "workspace box" : "no bounds", static_cast<double>(stats.points - stats.skipped_workspace - stats.skipped_invalid),
               in.median, in.low, in.high, static_cast<double>(env.octree().node_count()), env.octree().memory_bytes() / 1024.0,
               t.solids.median, use ? base_insert - in.median : na, use ? base_query - t.solids.median : na,
               static_cast<double>(t.colliding)});
  }
  table.note("The box is the node's default workspace (panda's reach " + bench::format(checker.reach()) +
             " m + 0.5 m); the floor and wall beyond it are dropped. Colliding states must be equal: nothing the robot "
             "can reach is lost.");
  table.write(dir);
}
}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  using namespace bvh_collision::environment_bench;
  const bool quick = bench::quick_mode(argc, argv);
  const Sizes sizes = quick ? Sizes{1, 40, 120, 100, {0.05, 0.1}, {16, 256}, 5, {0.02}}
                            : Sizes{5, 1000, 600, 500, {0.02, 0.05, 0.1}, {16, 64, 256, 1024, 4096}, 100, {0.005, 0.01, 0.02}};
  const std::string dir = bench::output_dir(argc, argv);
  std::printf("# Environment: %s\n", bench::machine_description().c_str());
  const Vec3 camera(-0.4, 0.0, 1.4);
  const std::vector<ScanPoint> scan = table_scene(camera, nullptr, sizes.width, sizes.height);
  const CollisionChecker checker = test::load_checker("panda");
  const auto states = random_states(checker.model(), sizes.states, 5);
  insertion_table(scan, camera, sizes, dir);
  resolution_table(scan, camera, checker, states, sizes, dir);
  {
    CheckerOptions levels;
    levels.proxy_levels = sizes.proxy_levels;
    speed_error_octree_table(scan, camera, test::load_checker("panda", levels), states, sizes, dir);
  }
  motion_table(sizes, dir);
  live_world_table(sizes, dir);
  clutter_table(checker, states, sizes, dir);
  voxel_error_table(checker, sizes, dir);
  workspace_table(scan, camera, checker, states, sizes, dir);
  self_filter(camera, 0.02, 0.04, sizes, dir);  // padding above the voxel diagonal: no cube reaches a link
  snapshot_table(sizes, dir);
  clearing_table(quick, dir);
  insertion_cpu_table(quick, dir);
  return 0;
}
