// Mesh-pair benchmark: boolean collision and distance between real link meshes in random
// near-contact poses, for every volume type, side by side with FCL on the same poses.
// Usage: bench_mesh_pair [OUTPUT_DIR] [--quick]
#include <cstring>
#include <iostream>
#include <map>

#include "../test/fcl_oracle.h"
#include "../test/mesh_fixtures.h"
#include "bench_util.h"

namespace bvh_collision {
namespace {

using bench::mean;
using bench::median;
using bench::time_us;

struct Case {
  std::string name;
  TriangleMesh a, b;
  std::vector<Transform> poses;    // b in a's frame
  std::vector<bool> collides;      // exact answers, meshes as surfaces (as FCL sees them)
  std::vector<double> distances;
  int contained = 0;               // poses where a closed mesh holds the other: 0 as solids
};

struct Row {
  std::string name;
  std::vector<double> times;
  double nv = 0, np = 0;
  int disagreements = 0;
};

std::vector<Case> make_cases(int poses_per_pair, std::mt19937_64& rng) {
  const std::string panda = "panda/moveit_resources_panda_description/meshes/collision/";
  const std::string ur5e = "ur5e/ur_description/meshes/ur5e/collision/";
  const std::pair<std::string, std::string> files[] = {
      {panda + "link3.stl", panda + "link4.stl"}, {panda + "link5.stl", panda + "link7.stl"},
      {panda + "hand.stl", panda + "finger.stl"}, {ur5e + "forearm.stl", ur5e + "wrist1.stl"},
      {ur5e + "upperarm.stl", ur5e + "wrist2.stl"}};
  std::vector<Case> cases;
  for (const auto& [fa, fb] : files) {
    Case c{fa.substr(fa.rfind('/') + 1) + "/" + fb.substr(fb.rfind('/') + 1), test::robot_mesh(fa), test::robot_mesh(fb), {}, {}, {}};
    const auto ga = Bvh<Aabb>::build(c.a), gb = Bvh<Aabb>::build(c.b);
    CollisionRequest surfaces;
    surfaces.solids = false;
    for (int p = 0; p < poses_per_pair; ++p) {
      c.poses.push_back(test::near_contact_pose(rng, ga, gb));
      c.collides.push_back(collide(ga, Transform(), gb, c.poses.back(), surfaces).collision);
      DistanceRequest surface;
      surface.solids = false;
      c.distances.push_back(distance(ga, Transform(), gb, c.poses.back(), surface).distance);
      c.contained += c.distances.back() > 0.0 && distance(ga, Transform(), gb, c.poses.back()).distance == 0.0;
    }
    cases.push_back(std::move(c));
  }
  return cases;
}

template <class BV>
std::pair<Row, Row> measure_ours(const std::vector<Case>& cases, BuildMethod method) {
  Row col{std::string("ours ") + volume_name<BV>()}, dist = col;
  CollisionRequest request;
  request.solids = false;  // FCL treats meshes as surfaces: compare the same query
  DistanceRequest surface;
  surface.solids = false;
  for (const Case& c : cases) {
    const auto a = Bvh<BV>::build(c.a, {method}), b = Bvh<BV>::build(c.b, {method});
    for (std::size_t p = 0; p < c.poses.size(); ++p) {
      CollisionResult r;
      col.times.push_back(time_us([&] { r = collide(a, Transform(), b, c.poses[p], request); }));
      col.nv += r.stats.volume_tests;
      col.np += r.stats.primitive_tests;
      col.disagreements += r.collision != c.collides[p];
      DistanceResult d;
      dist.times.push_back(time_us([&] { d = distance(a, Transform(), b, c.poses[p], surface); }));
      dist.nv += d.stats.volume_tests;
      dist.np += d.stats.primitive_tests;
      dist.disagreements += std::abs(d.distance - c.distances[p]) > 1e-9 * (1 + c.distances[p]);
    }
  }
  col.nv /= col.times.size();
  col.np /= col.times.size();
  dist.nv /= dist.times.size();
  dist.np /= dist.times.size();
  return {col, dist};
}

template <class FclBV>
Row measure_fcl(const std::vector<Case>& cases, const char* name, bool distance_query) {
  Row row{name};
  for (const Case& c : cases) {
    const auto a = test::fcl_model<FclBV>(c.a), b = test::fcl_model<FclBV>(c.b);
    fcl::CollisionObjectd oa(a, fcl::Transform3d::Identity()), ob(b, fcl::Transform3d::Identity());
    for (std::size_t p = 0; p < c.poses.size(); ++p) {
      ob.setTransform(test::fcl_transform(c.poses[p]));
      ob.computeAABB();
      if (distance_query) {
        fcl::DistanceRequestd request;
        fcl::DistanceResultd result;
        row.times.push_back(time_us([&] { fcl::distance(&oa, &ob, request, result); }));
        if (std::abs(result.min_distance - c.distances[p]) > 1e-6 * (1 + c.distances[p])) {
          ++row.disagreements;
          std::cout << "# " << name << " disagrees on " << c.name << " pose " << p << ": FCL " << std::setprecision(12)
                    << result.min_distance << " (triangles " << result.b1 << ", " << result.b2 << "), ours "
                    << c.distances[p] << "\n";
        }
      } else {
        fcl::CollisionRequestd request;
        fcl::CollisionResultd result;
        row.times.push_back(time_us([&] { fcl::collide(&oa, &ob, request, result); }));
        // Grazing contacts (|d| < 1e-9) are where FCL's inexact triangle test may differ.
        if (result.isCollision() != c.collides[p] && (c.distances[p] > 1e-9 || c.collides[p])) {
          ++row.disagreements;
          std::cout << "# " << name << " disagrees on " << c.name << " pose " << p << ": FCL "
                    << result.isCollision() << ", ours " << c.collides[p] << ", distance " << c.distances[p] << "\n";
        }
      }
    }
  }
  return row;
}

void print_table(const std::string& title, const std::vector<Row>& rows, double baseline_median,
                 bench::FigureFile& figures, const std::string& key) {
  std::cout << "\n" << title << "\n"
            << "| checker | median us | mean us | FCL best / ours (median) | Nv | Np | disagreements |\n"
            << "|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows) {
    const double med = median(r.times);
    std::cout << "| " << r.name << " | " << std::fixed << std::setprecision(2) << med << " | " << mean(r.times)
              << " | " << baseline_median / med << "x | " << std::setprecision(0) << r.nv << " | " << r.np
              << " | " << r.disagreements << " |\n";
    figures.add(key + " " + r.name + " median", "us", med, r.name.rfind("FCL", 0) == 0 ? std::nullopt : std::optional<double>(baseline_median));
  }
}

template <class BV>
void tolerance_curve(const std::vector<Case>& cases, bench::FigureFile& figures) {
  std::cout << "\nTolerance curve (" << volume_name<BV>() << ", boolean collision; false positive: reported"
            << " collision at true distance > 0; false negative: missed collision)\n"
            << "| tolerance mm | median us | mean us | false positives | largest FP distance mm | false negatives |\n"
            << "|---|---|---|---|---|---|\n";
  for (double eps : {0.0, 0.001, 0.002, 0.005, 0.01, 0.02}) {
    std::vector<double> times;
    int fp = 0, fn = 0, n = 0;
    double worst = 0.0;
    CollisionRequest request;
    request.solids = false;
    request.tolerance = eps;
    for (const Case& c : cases) {
      const auto a = Bvh<BV>::build(c.a), b = Bvh<BV>::build(c.b);
      for (std::size_t p = 0; p < c.poses.size(); ++p, ++n) {
        CollisionResult r;
        times.push_back(time_us([&] { r = collide(a, Transform(), b, c.poses[p], request); }));
        if (r.collision && !c.collides[p]) {
          ++fp;
          worst = std::max(worst, c.distances[p]);
        }
        fn += !r.collision && c.collides[p];
      }
    }
    std::cout << "| " << eps * 1000 << " | " << std::setprecision(2) << median(times) << " | " << mean(times) << " | "
              << std::setprecision(1) << 100.0 * fp / n << "% | " << std::setprecision(3) << worst * 1000 << " | " << fn
              << " |\n";
    figures.add("tolerance " + std::to_string(eps * 1000).substr(0, 4) + " mm median", "us", median(times));
    figures.add("tolerance " + std::to_string(eps * 1000).substr(0, 4) + " mm false positive rate", "%", 100.0 * fp / n);
    figures.add("tolerance " + std::to_string(eps * 1000).substr(0, 4) + " mm false negatives", "count", fn);
  }
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  const bool quick = argc > 2 && std::strcmp(argv[2], "--quick") == 0;
  std::mt19937_64 rng(2026);
  const std::vector<Case> cases = make_cases(quick ? 20 : 1000, rng);
  std::size_t poses = 0;
  for (const Case& c : cases) poses += c.poses.size();
  int contained = 0;
  for (const Case& c : cases) contained += c.contained;
  std::cout << "# Mesh pairs: " << cases.size() << " pairs of real link meshes, " << poses
            << " near-contact poses\n# Machine: " << bench::machine_description() << "\n"
            << "# Meshes compared as surfaces, as FCL sees them. In " << contained << " poses a closed mesh lies"
            << " wholly inside the other: there FCL reports the surface distance and no collision, while"
            << " bvh_collision's default (solids) reports collision at distance 0.\n";

  bench::FigureFile figures("mesh_pair");
  std::vector<Row> col, dist;
  col.push_back(measure_fcl<fcl::OBBRSSd>(cases, "FCL OBBRSS", false));
  col.push_back(measure_fcl<fcl::OBBd>(cases, "FCL OBB", false));
  dist.push_back(measure_fcl<fcl::RSSd>(cases, "FCL RSS", true));
  dist.push_back(measure_fcl<fcl::OBBRSSd>(cases, "FCL OBBRSS", true));
  auto add = [&](auto rows) {
    col.push_back(rows.first);
    dist.push_back(rows.second);
  };
  add(measure_ours<Aabb>(cases, BuildMethod::kSah));
  add(measure_ours<Obb>(cases, BuildMethod::kSah));
  add(measure_ours<Sphere>(cases, BuildMethod::kSah));
  add(measure_ours<Kdop14>(cases, BuildMethod::kSah));
  add(measure_ours<Kdop18>(cases, BuildMethod::kSah));
  add(measure_ours<Kdop26>(cases, BuildMethod::kSah));
  add(measure_ours<Rss>(cases, BuildMethod::kSah));
  const double fcl_col = std::min(median(col[0].times), median(col[1].times));
  const double fcl_dist = std::min(median(dist[0].times), median(dist[1].times));
  print_table("Boolean collision (surfaces), per query", col, fcl_col, figures, "collision");
  print_table("Distance, per query", dist, fcl_dist, figures, "distance");
  tolerance_curve<Obb>(cases, figures);
  figures.write(bench::output_dir(argc, argv));
  return 0;
}
