// Environment benchmark: scan insertion against octomap::OcTree::insertPointCloud on the same
// depth-camera view of a table scene (identical trees required), and the robot against that
// octree against FCL's OcTree collision (same poses, same octree, boolean answers compared).
#include <fcl/fcl.h>
#include <octomap/OcTree.h>

#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>

#include "bench_util.h"
#include "bvh_collision/checker/collision_checker.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "fcl_oracle.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

struct SceneBox {
  Vec3 lo, hi;
};

// A depth camera (600 x 500 rays, 70 x 58 degrees) above and behind a robot, looking at a table
// with boxes on it, a floor and a wall; 2 mm depth noise; rays that hit nothing return NaN.
std::vector<ScanPoint> table_scene(const Vec3& camera) {
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
  std::vector<double> ours, theirs;
  bool same = true;
  for (int r = 0; r < 5; ++r) {
    Octree tree(resolution);
    octomap::OcTree reference(resolution);
    ours.push_back(bench::time_us([&] { insert_scan(tree, scan, camera.cast<float>()); }) * 1e-6);
    theirs.push_back(bench::time_us([&] { reference.insertPointCloud(cloud, origin); }) * 1e-6);
    if (r == 0) same = leaves_of(tree) == leaves_of(reference);
  }
  const double a = bench::median(ours), b = bench::median(theirs);
  const double points = static_cast<double>(scan.size());
  std::printf("| insert %.2f m | %.3f s (%.2f Mpt/s) | %.3f s (%.2f Mpt/s) | %.1fx | %s |\n", resolution, a,
              points / a * 1e-6, b, points / b * 1e-6, b / a, same ? "identical" : "DIFFERENT");
  const std::string name = "insert_" + std::to_string(static_cast<int>(std::lround(resolution * 100))) + "cm";
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
  const std::string dir = test::robots_dir() + "/panda";
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
  const CollisionChecker checker(model, AllowedCollisionMatrix::adjacent_links(model));
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
  for (int i = 0; i < n; ++i) {
    bool ours = false, theirs = false;
    ours_us[i] = bench::time_us([&] { ours = checker.check_environment(states[i].data(), env, request).collision; });
    fcl_us[i] = bench::time_us([&] {
      forward_kinematics(checker.model(), states[i].data(), poses);
      for (std::size_t k = 0; k < links.objects.size() && !theirs; ++k) {
        links.objects[k]->setTransform(test::fcl_transform(poses[links.link[k]] * links.origin[k]));
        links.objects[k]->computeAABB();
        fcl::CollisionRequestd r;
        fcl::CollisionResultd result;
        theirs = fcl::collide(links.objects[k].get(), &fcl_octree, r, result) > 0;
      }
    });
    solids_us[i] = bench::time_us([&] { checker.check_environment(states[i].data(), env, solids); });
    dist_us[i] = bench::time_us([&] { checker.check_environment(states[i].data(), env, distance); });
    disagree += ours != theirs;
    colliding += ours;
  }
  const double a = bench::median(ours_us), b = bench::median(fcl_us);
  std::printf("| panda vs octree %.2f m (%zu nodes) | %.1f us (mean %.1f) | %.1f us (mean %.1f) | %.1fx | %d of %d colliding, %d disagreements |\n",
              resolution, env.octree().node_count(), a, bench::mean(ours_us), b, bench::mean(fcl_us), b / a, colliding, n,
              disagree);
  std::printf("| panda vs octree %.2f m, solids (the default) | %.1f us (mean %.1f) | | | |\n", resolution,
              bench::median(solids_us), bench::mean(solids_us));
  std::printf("| panda distance to octree %.2f m | %.1f us (mean %.1f) | | | |\n", resolution, bench::median(dist_us),
              bench::mean(dist_us));
  const std::string name = "panda_octree_" + std::to_string(static_cast<int>(std::lround(resolution * 100))) + "cm";
  figures.add(name + "_boolean_median", "us", a, b);
  figures.add(name + "_boolean_mean", "us", bench::mean(ours_us), bench::mean(fcl_us));
  figures.add(name + "_solids_median", "us", bench::median(solids_us));
  figures.add(name + "_distance_median", "us", bench::median(dist_us));
  figures.add(name + "_disagreements", "states", disagree);
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
  figures.write(bench::output_dir(argc, argv));
  return 0;
}
