// Environment benchmark: scan insertion against octomap::OcTree::insertPointCloud on the same
// depth-camera view of a table scene (identical trees required), and the robot against that
// octree against FCL's OcTree collision (same poses, same octree, boolean answers compared).
#include <fcl/fcl.h>
#include <octomap/OcTree.h>

#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <random>
#include <sstream>

#include "bench_util.h"
#include "bvh_collision/checker/collision_checker.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "fcl_oracle.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

struct SceneBox {
  Vec3 lo, hi;
};

// The distance along a ray (unit direction) to something more in the scene than the boxes, if
// nearer than `best`: the robot, for the self-filter figures.
using ExtraHit = std::function<double(const Vec3& origin, const Vec3& direction, double best)>;

// A depth camera (600 x 500 rays, 70 x 58 degrees) above and behind a robot, looking at a table
// with boxes on it, a floor and a wall; 2 mm depth noise; rays that hit nothing return NaN.
std::vector<ScanPoint> table_scene(const Vec3& camera, const ExtraHit& extra = nullptr) {
  const std::vector<SceneBox> boxes = {
      {{0.3, -0.6, 0.30}, {1.0, 0.6, 0.35}},   // table top
      {{0.5, -0.2, 0.35}, {0.6, -0.1, 0.50}},  // a box
      {{0.7, 0.1, 0.35}, {0.8, 0.3, 0.45}},    // another
      {{-5, -5, -0.1}, {5, 5, 0.0}},           // floor
      {{2.5, -5, 0.0}, {2.6, 5, 3.0}},         // wall
  };
  const Vec3 forward = Vec3(1.0, 0.0, -0.8).normalized(), right = Vec3(0, -1, 0), up = right.cross(forward) * -1.0;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<ScanPoint> points;
  const int width = 600, height = 500;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double x = std::tan(0.61) * (2.0 * (u + 0.5) / width - 1.0), y = std::tan(0.51) * (2.0 * (v + 0.5) / height - 1.0);
      const Vec3 d = (forward + x * right + y * up).normalized();
      double best = std::numeric_limits<double>::infinity();
      for (const SceneBox& b : boxes) {
        double t0 = 0.0, t1 = best;
        for (int a = 0; a < 3 && t0 <= t1; ++a) {
          const double s1 = (b.lo[a] - camera[a]) / d[a], s2 = (b.hi[a] - camera[a]) / d[a];
          t0 = std::max(t0, std::min(s1, s2));
          t1 = std::min(t1, std::max(s1, s2));
        }
        if (t0 <= t1) best = t0;
      }
      if (extra) best = extra(camera, d, best);
      const float nan = std::numeric_limits<float>::quiet_NaN();
      points.push_back(std::isfinite(best) && best < 6.0 ? ScanPoint((camera + (best + noise(rng)) * d).cast<float>())
                                                         : ScanPoint(nan, nan, nan));
    }
  }
  return points;
}

using LeafMap = std::map<std::tuple<int, int, int, int>, float>;
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

void insertion(const std::vector<ScanPoint>& scan, const Vec3& camera, double resolution, bench::FigureFile& figures) {
  octomap::Pointcloud cloud;
  for (const ScanPoint& p : scan) cloud.push_back(p.x(), p.y(), p.z());
  const octomap::point3d origin(camera.x(), camera.y(), camera.z());
  std::vector<double> ours, ours_one_core, theirs;
  bool same = true;
  ScanOptions one_core;
  one_core.threads = 1;
  for (int r = 0; r < 5; ++r) {
    Octree tree(resolution), single(resolution);
    octomap::OcTree reference(resolution);
    ours.push_back(bench::time_us([&] { insert_scan(tree, scan, camera.cast<float>()); }) * 1e-6);
    ours_one_core.push_back(bench::time_us([&] { insert_scan(single, scan, camera.cast<float>(), one_core); }) * 1e-6);
    theirs.push_back(bench::time_us([&] { reference.insertPointCloud(cloud, origin); }) * 1e-6);
    if (r == 0) same = leaves_of(tree) == leaves_of(reference);
  }
  const double a = bench::median(ours), b = bench::median(theirs);
  const double points = static_cast<double>(scan.size());
  std::printf("| insert %.2f m | %.3f s (%.2f Mpt/s) | %.3f s (%.2f Mpt/s) | %.1fx | %s |\n", resolution, a,
              points / a * 1e-6, b, points / b * 1e-6, b / a, same ? "identical" : "DIFFERENT");
  const double c = bench::median(ours_one_core);
  std::printf("| insert %.2f m, one core | %.3f s (%.2f Mpt/s) | %.3f s (%.2f Mpt/s) | %.1fx | |\n", resolution, c,
              points / c * 1e-6, b, points / b * 1e-6, b / c);
  const std::string name = "insert_" + std::to_string(static_cast<int>(std::lround(resolution * 100))) + "cm";
  figures.add(name + "_one_core", "s", c, b);
  figures.add(name, "s", a, b);
  figures.add(name + "_points_per_second", "1/s", points / a, points / b);
  figures.add(name + "_identical_to_octomap", "bool", same ? 1.0 : 0.0);
  if (!same) std::exit(1);
}

struct FclLinks {
  std::vector<std::shared_ptr<fcl::CollisionObjectd>> objects;
  std::vector<int> link;
  std::vector<Transform> origin;
};

void environment_check(const std::vector<ScanPoint>& scan, const Vec3& camera, double resolution,
                       bench::FigureFile& figures) {
  const CollisionChecker checker = test::load_checker("panda");
  Environment env(resolution);
  insert_scan(env.octree(), scan, camera.cast<float>());
  auto reference = std::make_shared<octomap::OcTree>(resolution);
  to_octomap(env.octree(), *reference);
  fcl::CollisionObjectd fcl_octree(std::make_shared<fcl::OcTreed>(reference));
  fcl_octree.computeAABB();
  FclLinks links;
  for (std::size_t l = 0; l < checker.model().links().size(); ++l) {
    for (const CollisionElement& e : checker.model().links()[l].collision) {
      links.objects.push_back(std::make_shared<fcl::CollisionObjectd>(test::fcl_model<fcl::OBBRSSd>(*e.mesh)));
      links.link.push_back(static_cast<int>(l));
      links.origin.push_back(e.origin);
    }
  }
  std::mt19937_64 rng(5);
  const int n = 2000;
  std::vector<std::vector<double>> states;
  for (int i = 0; i < n; ++i) states.push_back(random_configuration(checker.model(), rng));
  std::vector<double> ours_us(n), fcl_us(n), dist_us(n);
  std::vector<Transform> poses;
  EnvironmentRequest request;
  request.objects = false;
  request.solids = false;  // FCL's semantics
  EnvironmentRequest distance = request;
  distance.distance = true;
  EnvironmentRequest solids = request;  // the default: occupied cubes inside closed links count
  solids.solids = true;
  std::vector<double> solids_us(n);
  int disagree = 0, colliding = 0;
  // Each kind of query in its own pass over the states, so that none runs on caches another warmed.
  std::vector<char> ours(n, 0), theirs(n, 0);
  for (int i = 0; i < n; ++i) {
    ours_us[i] = bench::time_us([&] { ours[i] = checker.check_environment(states[i].data(), env, request).collision; });
  }
  for (int i = 0; i < n; ++i) {
    fcl_us[i] = bench::time_us([&] {
      forward_kinematics(checker.model(), states[i].data(), poses);
      for (std::size_t k = 0; k < links.objects.size() && !theirs[i]; ++k) {
        links.objects[k]->setTransform(test::fcl_transform(poses[links.link[k]] * links.origin[k]));
        links.objects[k]->computeAABB();
        fcl::CollisionRequestd r;
        fcl::CollisionResultd result;
        theirs[i] = fcl::collide(links.objects[k].get(), &fcl_octree, r, result) > 0;
      }
    });
  }
  for (int i = 0; i < n; ++i) solids_us[i] = bench::time_us([&] { checker.check_environment(states[i].data(), env, solids); });
  for (int i = 0; i < n; ++i) dist_us[i] = bench::time_us([&] { checker.check_environment(states[i].data(), env, distance); });
  for (int i = 0; i < n; ++i) {
    disagree += ours[i] != theirs[i];
    colliding += ours[i];
  }
  // FCL's distance on a subset (it takes 50 to 150 ms a state): the same minimum over links, free states.
  std::vector<double> fcl_dist_us, our_dist_us;
  double worst_gap = 0.0;
  for (int i = 0; i < n && fcl_dist_us.size() < 40; i += 7) {
    EnvironmentResult mine;
    const double t = bench::time_us([&] { mine = checker.check_environment(states[i].data(), env, distance); });
    if (mine.collision) continue;
    double theirs = std::numeric_limits<double>::infinity();
    fcl_dist_us.push_back(bench::time_us([&] {
      forward_kinematics(checker.model(), states[i].data(), poses);
      for (std::size_t k = 0; k < links.objects.size(); ++k) {
        links.objects[k]->setTransform(test::fcl_transform(poses[links.link[k]] * links.origin[k]));
        links.objects[k]->computeAABB();
        fcl::DistanceRequestd r;
        fcl::DistanceResultd result;
        fcl::distance(links.objects[k].get(), &fcl_octree, r, result);
        theirs = std::min(theirs, result.min_distance);
      }
    }));
    our_dist_us.push_back(t);
    worst_gap = std::max(worst_gap, std::abs(theirs - mine.min_distance));
  }
  const double a = bench::median(ours_us), b = bench::median(fcl_us);
  std::printf("| panda vs octree %.2f m (%zu nodes) | %.1f us (mean %.1f) | %.1f us (mean %.1f) | %.1fx | %d of %d colliding, %d disagreements |\n",
              resolution, env.octree().node_count(), a, bench::mean(ours_us), b, bench::mean(fcl_us), b / a, colliding, n,
              disagree);
  std::printf("| panda vs octree %.2f m, solids (the default) | %.1f us (mean %.1f) | | | |\n", resolution,
              bench::median(solids_us), bench::mean(solids_us));
  std::printf("| panda distance to octree %.2f m | %.1f us (mean %.1f) | | | |\n", resolution, bench::median(dist_us),
              bench::mean(dist_us));
  const double da = bench::median(our_dist_us), db = bench::median(fcl_dist_us);
  std::printf("| panda distance to octree %.2f m, %zu free states | %.1f us | %.1f us | %.1fx | largest difference %.1e m |\n",
              resolution, our_dist_us.size(), da, db, db / da, worst_gap);
  const std::string name = "panda_octree_" + std::to_string(static_cast<int>(std::lround(resolution * 100))) + "cm";
  figures.add(name + "_boolean_median", "us", a, b);
  figures.add(name + "_boolean_mean", "us", bench::mean(ours_us), bench::mean(fcl_us));
  figures.add(name + "_solids_median", "us", bench::median(solids_us));
  figures.add(name + "_distance_median", "us", bench::median(dist_us));
  figures.add(name + "_distance_free_states_median", "us", da, db);
  figures.add(name + "_distance_largest_difference", "m", worst_gap);
  figures.add(name + "_disagreements", "states", disagree);
}

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
void self_filter(const Vec3& camera, double resolution, double padding, bench::FigureFile& figures) {
  const CollisionChecker checker = test::load_checker("panda");
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
  const auto scan = table_scene(camera, [&](const Vec3& origin, const Vec3& direction, double best) {
    for (std::size_t m = 0; m < meshes.size(); ++m) {
      const RayHit hit = raycast(meshes[m], poses[m], origin, direction, std::min(best, 10.0));
      if (hit.hit) best = std::min(best, hit.distance);
    }
    return best;
  });
  const ScanPoint sensor = camera.cast<float>();
  std::vector<double> filter_s, filtered_insert_s, raw_insert_s;
  FilteredScan filtered;
  Octree raw(resolution), clean(resolution);
  for (int r = 0; r < 5; ++r) {
    raw = Octree(resolution);
    clean = Octree(resolution);
    filter_s.push_back(bench::time_us([&] { filtered = checker.filter_scan(state.data(), scan, sensor, padding); }) * 1e-6);
    filtered_insert_s.push_back(filter_s.back() + bench::time_us([&] {
      insert_scan(clean, filtered.obstacles, filtered.clear_only, sensor);
    }) * 1e-6);
    raw_insert_s.push_back(bench::time_us([&] { insert_scan(raw, scan, sensor); }) * 1e-6);
  }
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
  std::printf("| self filter %.2f m, padding %.2f m (%zu on robot, %zu shadowed) | %.3f s (%.2f Mpt/s) | | | |\n",
              resolution, padding, filtered.on_robot, filtered.shadowed, f, points / f * 1e-6);
  std::printf("| filter + insert %.2f m | %.3f s | %.3f s (raw insert) | %.2fx | occupied voxels on the robot: %d raw, %d filtered |\n",
              resolution, fi, ri, ri / fi, raw_on, clean_on);
  std::printf("| panda against the octree it built | %zu links collide (filtered) | %zu links collide (raw) | | |\n",
              clean_hit.contacts.size(), raw_hit.contacts.size());
  const std::string name = "self_filter_" + std::to_string(static_cast<int>(std::lround(resolution * 100))) + "cm";
  figures.add(name, "s", f);
  figures.add(name + "_points_per_second", "1/s", points / f);
  figures.add(name + "_with_insert", "s", fi, ri);
  figures.add(name + "_points_on_robot", "points", static_cast<double>(filtered.on_robot));
  figures.add(name + "_points_shadowed", "points", static_cast<double>(filtered.shadowed));
  figures.add(name + "_voxels_on_robot", "voxels", clean_on, raw_on);
  figures.add(name + "_links_colliding", "links", static_cast<double>(clean_hit.contacts.size()),
              static_cast<double>(raw_hit.contacts.size()));
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  std::printf("# Environment: %s\n\n", bench::machine_description().c_str());
  const Vec3 camera(-0.4, 0.0, 1.4);
  const std::vector<ScanPoint> scan = table_scene(camera);
  std::printf("Table scene: %zu points from a depth camera at (%.1f, %.1f, %.1f); medians of 5 runs.\n\n", scan.size(),
              camera.x(), camera.y(), camera.z());
  std::printf("| query | ours | baseline (OctoMap / FCL) | speed-up | agreement |\n|---|---|---|---|---|\n");
  bench::FigureFile figures("environment");
  for (const double res : {0.02, 0.05}) insertion(scan, camera, res, figures);
  for (const double res : {0.02, 0.05}) environment_check(scan, camera, res, figures);
  self_filter(camera, 0.02, 0.04, figures);  // padding above the voxel diagonal: no cube reaches a link
  figures.write(bench::output_dir(argc, argv));
  return 0;
}
