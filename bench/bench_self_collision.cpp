// Self-collision benchmark: microseconds per configuration for boolean, all-pairs and distance
// queries, against an FCL pipeline built as MoveIt builds it (BVHModel<OBBRSS> per mesh,
// fcl::Sphere for spheres, DynamicAABBTreeCollisionManager, the same allowed-collision matrix
// applied in the callbacks), on the same uniform random configurations; and FK on its own.
// Usage: bench_self_collision [OUTPUT_DIR] [--quick]
#include <cstring>
#include <functional>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
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

constexpr int kRepeats = 3;  // repetitions of the cheap (boolean) blocks

using Query = std::function<void(int, const double*)>;

// Per-state times of queries, each run over every state in a block, as a planner calls it (warm
// caches for both libraries). The blocks are interleaved and repeated, so that drift in this
// shared machine's load reaches every query alike; a state's time is its median over repeats.
std::vector<std::vector<double>> per_state(const std::vector<std::vector<double>>& states,
                                           const std::vector<Query>& queries, int repeats) {
  const int n = static_cast<int>(states.size());
  std::vector<std::vector<std::vector<double>>> t(queries.size(), std::vector<std::vector<double>>(n));
  for (int r = 0; r < repeats; ++r) {
    for (std::size_t q = 0; q < queries.size(); ++q) {
      for (int i = 0; i < n; ++i) t[q][i].push_back(time_us([&] { queries[q](i, states[i].data()); }));
    }
  }
  std::vector<std::vector<double>> out(queries.size());
  for (std::size_t q = 0; q < queries.size(); ++q) {
    for (int i = 0; i < n; ++i) out[q].push_back(median(t[q][i]));
  }
  return out;
}

struct FclPipeline {
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::vector<int> link;  // per object
  std::vector<Transform> origin;
  fcl::DynamicAABBTreeCollisionManagerd manager;
  const AllowedCollisionMatrix* acm = nullptr;
};

struct CallbackData {
  explicit CallbackData(const FclPipeline* p, bool every_pair = false) : pipeline(p), all_pairs(every_pair) {}
  const FclPipeline* pipeline;
  bool hit = false;
  double distance = std::numeric_limits<double>::infinity();
  bool all_pairs = false;                      // collision: keep going, collect every pair
  std::set<std::pair<int, int>> pairs;         // colliding link pairs (a < b) when all_pairs
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
  if (d->all_pairs && result.isCollision()) d->pairs.insert({std::min(a, b), std::max(a, b)});
  return d->hit && !d->all_pairs;  // boolean: stop at the first collision
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

// Boolean self-collision at a tolerance (DESIGN.md section 2: "collision" may be answered for
// states up to `tolerance` apart, never "free" for a colliding one), against the exact answers.
void tolerance_rows(const std::string& robot, const CollisionChecker& checker,
                    const std::vector<std::vector<double>>& states, const std::vector<SelfCollisionResult>& exact,
                    double fcl_mean, bench::FigureFile& figures) {
  std::cout << "\n| tolerance | ours median us | ours mean us | FCL/ours (mean, FCL exact) | false positives |"
               " largest true distance of a false positive | false negatives |\n|---|---|---|---|---|---|---|\n";
  for (const double tolerance : {0.0, 0.01, 0.02}) {
    SelfCollisionRequest request;
    request.solids = false;
    request.tolerance = tolerance;
    std::vector<char> hit(states.size());
    const auto t = per_state(
        states, {[&](int i, const double* s) { hit[i] = checker.check_self(s, request).collision; }}, kRepeats)[0];
    int false_positive = 0, false_negative = 0;
    double worst = 0.0;
    for (std::size_t i = 0; i < states.size(); ++i) {
      const bool truth = exact[i].min_distance <= 0.0;
      false_negative += truth && !hit[i];
      if (hit[i] && !truth) {
        ++false_positive;
        worst = std::max(worst, exact[i].min_distance);
      }
    }
    const double rate = 100.0 * false_positive / states.size();
    std::cout << "| " << tolerance * 1000 << " mm | " << median(t) << " | " << mean(t) << " | " << fcl_mean / mean(t)
              << "x | " << false_positive << " (" << rate << " %) | " << worst * 1000 << " mm | " << false_negative << " |\n";
    const std::string name = robot + " boolean tolerance " + std::to_string(static_cast<int>(tolerance * 1000)) + " mm";
    figures.add(name + " mean", "us", mean(t), fcl_mean);
    figures.add(name + " false positives", "%", rate);
    figures.add(name + " false negatives", "count", false_negative);
  }
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
  // Boolean queries are cheap: kRepeats interleaved repetitions; distance once.
  std::vector<SelfCollisionResult> ours_bool(n), ours_dist(n);
  std::vector<CallbackData> fcl_bool(n, CallbackData(&fcl_pipeline)), fcl_dist(n, CallbackData(&fcl_pipeline));
  const Query fk = [&](int, const double* s) { forward_kinematics(checker.model(), s, poses); };
  const Query ours_boolean = [&](int i, const double* s) { ours_bool[i] = checker.check_self(s, boolean); };
  const Query ours_solids = [&](int, const double* s) { checker.check_self(s); };
  std::vector<SelfCollisionResult> ours_all_pairs(n);
  std::vector<CallbackData> fcl_all(n, CallbackData(&fcl_pipeline));
  const Query ours_all = [&](int i, const double* s) { ours_all_pairs[i] = checker.check_self(s, all); };
  const Query fcl_all_pairs = [&](int i, const double* s) {
    forward_kinematics(checker.model(), s, poses);
    move_pipeline(fcl_pipeline, poses);
    fcl_all[i] = CallbackData(&fcl_pipeline, true);
    fcl_pipeline.manager.collide(&fcl_all[i], collision_callback);
  };
  const Query fcl_boolean = [&](int i, const double* s) {
    forward_kinematics(checker.model(), s, poses);
    move_pipeline(fcl_pipeline, poses);
    fcl_bool[i] = CallbackData(&fcl_pipeline);
    fcl_pipeline.manager.collide(&fcl_bool[i], collision_callback);
  };
  const auto cheap =
      per_state(states, {fk, ours_boolean, fcl_boolean, ours_solids, ours_all, fcl_all_pairs}, kRepeats);
  const auto& [t_fk, t_bool, f_bool, t_bool_solids, t_all, f_all] =
      std::tie(cheap[0], cheap[1], cheap[2], cheap[3], cheap[4], cheap[5]);
  const auto costly = per_state(
      states, {[&](int i, const double* s) { ours_dist[i] = checker.check_self(s, dist); },
       [&](int i, const double* s) {
         forward_kinematics(checker.model(), s, poses);
         move_pipeline(fcl_pipeline, poses);
         fcl_pipeline.manager.distance(&fcl_dist[i], distance_callback);
       }},
      1);
  const auto& [t_dist, f_dist] = std::tie(costly[0], costly[1]);
  int disagree_bool = 0, disagree_dist = 0, disagree_all = 0, colliding = 0;
  for (int i = 0; i < n; ++i) {
    colliding += ours_bool[i].collision;
    const auto& found = ours_all_pairs[i].colliding_pairs;
    disagree_all += std::set<std::pair<int, int>>(found.begin(), found.end()) != fcl_all[i].pairs;
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
      figures.add(robot + " " + name + " median", "us", median(ours), median(*fcl));
    } else {
      std::cout << "- | - | - | - |\n";
      figures.add(robot + " " + name + " mean", "us", mean(ours));
    }
  };
  row("boolean", t_bool, &f_bool, disagree_bool);
  row("distance", t_dist, &f_dist, disagree_dist);
  row("boolean, solids", t_bool_solids, nullptr, 0);
  row("all pairs", t_all, &f_all, disagree_all);
  row("forward kinematics", t_fk, nullptr, 0);
  tolerance_rows(robot, checker, states, ours_dist, mean(f_bool), figures);
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
