// Self-collision benchmark: microseconds per configuration for boolean, all-pairs and distance
// queries, against an FCL pipeline built as MoveIt builds it (BVHModel<OBBRSS> per mesh,
// fcl::Sphere for spheres, DynamicAABBTreeCollisionManager, the same allowed-collision matrix
// applied in the callbacks), on the same uniform random configurations; and FK on its own.
// Usage: bench_self_collision [OUTPUT_DIR] [--quick]
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include "../test/fcl_oracle.h"
#include "bench_util.h"
#include "bvh_collision/checker/collision_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

using bench::mean;
using bench::median;
using bench::time_us;

struct FclPipeline {
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::vector<int> link;  // per object
  std::vector<Transform> origin;
  fcl::DynamicAABBTreeCollisionManagerd manager;
  const AllowedCollisionMatrix* acm = nullptr;
};

struct CallbackData {
  const FclPipeline* pipeline;
  bool hit = false;
  double distance = std::numeric_limits<double>::infinity();
};

int link_of(const FclPipeline& p, fcl::CollisionObjectd* o) { return p.link[reinterpret_cast<std::intptr_t>(o->getUserData())]; }

bool collision_callback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* raw) {
  auto* d = static_cast<CallbackData*>(raw);
  const int a = link_of(*d->pipeline, o1), b = link_of(*d->pipeline, o2);
  if (a == b || d->pipeline->acm->allowed(a, b)) return false;
  fcl::CollisionRequestd request;
  fcl::CollisionResultd result;
  fcl::collide(o1, o2, request, result);
  d->hit = d->hit || result.isCollision();
  return d->hit;  // stop at the first collision
}

bool distance_callback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* raw, double& dist) {
  auto* d = static_cast<CallbackData*>(raw);
  const int a = link_of(*d->pipeline, o1), b = link_of(*d->pipeline, o2);
  if (a == b || d->pipeline->acm->allowed(a, b)) {
    dist = d->distance;
    return false;
  }
  fcl::DistanceRequestd request;
  fcl::DistanceResultd result;
  fcl::distance(o1, o2, request, result);
  d->distance = std::min(d->distance, std::max(0.0, result.min_distance));
  dist = d->distance;
  return d->distance <= 0.0;
}

void build_pipeline(const RobotModel& m, const AllowedCollisionMatrix& acm, FclPipeline& p) {
  p.acm = &acm;
  std::map<const TriangleMesh*, std::shared_ptr<fcl::CollisionGeometryd>> shared;
  for (std::size_t l = 0; l < m.links().size(); ++l) {
    for (const CollisionElement& e : m.links()[l].collision) {
      std::shared_ptr<fcl::CollisionGeometryd> g;
      if (e.shape == CollisionElement::Shape::kSphere) {
        g = std::make_shared<fcl::Sphered>(e.radius);
      } else if (auto it = shared.find(e.mesh.get()); it != shared.end()) {
        g = it->second;
      } else {
        g = shared[e.mesh.get()] = test::fcl_model<fcl::OBBRSSd>(*e.mesh);
      }
      p.objects.push_back(std::make_unique<fcl::CollisionObjectd>(g));
      p.objects.back()->setUserData(reinterpret_cast<void*>(static_cast<std::intptr_t>(p.link.size())));
      p.link.push_back(static_cast<int>(l));
      p.origin.push_back(e.origin);
    }
  }
  for (auto& o : p.objects) p.manager.registerObject(o.get());
  p.manager.setup();
}

void move_pipeline(FclPipeline& p, const std::vector<Transform>& poses) {
  for (std::size_t i = 0; i < p.objects.size(); ++i) {
    p.objects[i]->setTransform(test::fcl_transform(poses[p.link[i]] * p.origin[i]));
    p.objects[i]->computeAABB();
  }
  p.manager.update();
}

std::vector<std::vector<double>> random_states(const RobotModel& m, int n, std::mt19937_64& rng) {
  std::vector<std::vector<double>> out;
  for (int i = 0; i < n; ++i) out.push_back(random_configuration(m, rng));
  return out;
}

void run_robot(const std::string& robot, int n, bench::FigureFile& figures) {
  const std::string dir = test::robots_dir() + "/" + robot;
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  if (std::ifstream in(dir + "/robot.srdf"); in) {
    std::ostringstream s;
    s << in.rdbuf();
    apply_srdf(parse_srdf(s.str()), model, acm);
  }
  const CollisionChecker checker(model, acm);
  FclPipeline fcl_pipeline;
  build_pipeline(checker.model(), checker.acm(), fcl_pipeline);
  std::mt19937_64 rng(99);
  const auto states = random_states(checker.model(), n, rng);
  std::vector<Transform> poses;
  SelfCollisionRequest boolean, all, dist;
  boolean.solids = all.solids = dist.solids = false;  // FCL's semantics for the comparison
  all.all_pairs = true;
  dist.distance = true;
  // Each query type runs over every state in a block, as a planner calls it (warm caches for
  // both libraries), timed per call.
  std::vector<SelfCollisionResult> ours_bool(n), ours_dist(n);
  std::vector<CallbackData> fcl_bool(n, CallbackData{&fcl_pipeline}), fcl_dist(n, CallbackData{&fcl_pipeline});
  auto per_state = [&](auto&& query) {
    std::vector<double> t;
    for (int i = 0; i < n; ++i) t.push_back(time_us([&] { query(i, states[i].data()); }));
    return t;
  };
  const auto t_fk = per_state([&](int, const double* s) { forward_kinematics(checker.model(), s, poses); });
  const auto t_bool = per_state([&](int i, const double* s) { ours_bool[i] = checker.check_self(s, boolean); });
  const auto t_bool_solids = per_state([&](int, const double* s) { checker.check_self(s); });
  const auto t_all = per_state([&](int, const double* s) { checker.check_self(s, all); });
  const auto t_dist = per_state([&](int i, const double* s) { ours_dist[i] = checker.check_self(s, dist); });
  const auto f_bool = per_state([&](int i, const double* s) {
    forward_kinematics(checker.model(), s, poses);
    move_pipeline(fcl_pipeline, poses);
    fcl_pipeline.manager.collide(&fcl_bool[i], collision_callback);
  });
  const auto f_dist = per_state([&](int i, const double* s) {
    forward_kinematics(checker.model(), s, poses);
    move_pipeline(fcl_pipeline, poses);
    fcl_pipeline.manager.distance(&fcl_dist[i], distance_callback);
  });
  int disagree_bool = 0, disagree_dist = 0, colliding = 0;
  for (int i = 0; i < n; ++i) {
    colliding += ours_bool[i].collision;
    disagree_bool += ours_bool[i].collision != fcl_bool[i].hit;
    disagree_dist += std::abs(ours_dist[i].min_distance - fcl_dist[i].distance) > 1e-6;
  }
  std::cout << "\n## " << robot << ": " << checker.checked_pairs().size() << " checked pairs, " << n
            << " uniform random states (" << colliding << " in collision)\n"
            << "| query | ours median us | ours mean us | FCL median us | FCL mean us | FCL/ours (mean) | disagreements |\n"
            << "|---|---|---|---|---|---|---|\n"
            << std::fixed << std::setprecision(2);
  auto row = [&](const std::string& name, const std::vector<double>& ours, const std::vector<double>* fcl, int disagreements) {
    std::cout << "| " << name << " | " << median(ours) << " | " << mean(ours) << " | ";
    if (fcl) {
      std::cout << median(*fcl) << " | " << mean(*fcl) << " | " << mean(*fcl) / mean(ours) << "x | " << disagreements << " |\n";
      figures.add(robot + " " + name + " mean", "us", mean(ours), mean(*fcl));
    } else {
      std::cout << "- | - | - | - |\n";
      figures.add(robot + " " + name + " mean", "us", mean(ours));
    }
  };
  row("boolean", t_bool, &f_bool, disagree_bool);
  row("distance", t_dist, &f_dist, disagree_dist);
  row("boolean, solids", t_bool_solids, nullptr, 0);
  row("all pairs", t_all, nullptr, 0);
  row("forward kinematics", t_fk, nullptr, 0);
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  const bool quick = argc > 2 && std::strcmp(argv[2], "--quick") == 0;
  std::cout << "# Self-collision per configuration, against FCL as MoveIt uses it (FK included in FCL's time,"
            << " as in ours)\n# Machine: " << bench::machine_description() << "\n";
  bench::FigureFile figures("self_collision");
  for (const char* robot : {"panda", "ur5e", "pr2"}) run_robot(robot, quick ? 200 : 10000, figures);
  figures.write(bench::output_dir(argc, argv));
  return 0;
}
