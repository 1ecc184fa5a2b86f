// Self-collision benchmark, sections 1, 2 and 5 of the report (make bench): per robot, time per
// configuration against the tolerance with the false positives and negatives it costs; distance
// time against the allowed error; and what modelling only what the scene needs saves (the
// allowed-collision matrix, sampled never-colliding pairs, checking only the pairs a motion
// moves). FCL runs as MoveIt runs it (BVHModel<OBBRSS> per mesh, fcl::Sphere for spheres,
// DynamicAABBTreeCollisionManager, the same allowed-collision matrix applied in the callbacks) on
// the same uniform random configurations, FK included in both.
// Usage: bench_self_collision [OUTPUT_DIR] [--quick]
#include <functional>
#include <fstream>
#include <iostream>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "../test/fcl_oracle.h"
#include "bench_util.h"
#include "bvh_collision/query/acm_sampling.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

using bench::Spread;
using bench::Table;
using Query = std::function<void(std::size_t)>;  // runs one query on state i

const double kTolerancesMm[] = {0, 1, 2, 5, 10, 20};

struct Sizes {
  std::size_t states, distance_states, runs, samples;
};

// Time per state of each query, as the median over `runs` runs with the spread. In each run
// every query runs over all states in turn (warm caches for both libraries, as a planner calls
// them), so that drift in the machine's load reaches every query alike.
std::vector<Spread> timed_runs(std::size_t n, const std::vector<Query>& queries, std::size_t runs) {
  std::vector<std::vector<double>> t(queries.size());
  for (std::size_t r = 0; r < runs; ++r) {
    for (std::size_t q = 0; q < queries.size(); ++q) {
      t[q].push_back(bench::us_per_item(n, [&] {
        for (std::size_t i = 0; i < n; ++i) queries[q](i);
      }));
    }
  }
  std::vector<Spread> out;
  for (const auto& runs_of_q : t) out.push_back(bench::spread(runs_of_q));
  return out;
}

// ------------------------------------------------------------------------------ FCL pipeline

struct FclPipeline {
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects;
  std::vector<int> link;  // per object
  std::vector<Transform> origin;
  fcl::DynamicAABBTreeCollisionManagerd manager;
  const AllowedCollisionMatrix* acm = nullptr;
};

struct CallbackData {
  const FclPipeline* pipeline = nullptr;
  bool hit = false;
  double distance = std::numeric_limits<double>::infinity();
  fcl::DistanceRequestd distance_request;
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
  return d->hit;  // boolean: stop at the first collision
}

bool distance_callback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* raw, double& dist) {
  auto* d = static_cast<CallbackData*>(raw);
  const int a = link_of(*d->pipeline, o1), b = link_of(*d->pipeline, o2);
  if (a != b && !d->pipeline->acm->allowed(a, b)) {
    fcl::DistanceResultd result;
    fcl::distance(o1, o2, d->distance_request, result);
    d->distance = std::min(d->distance, std::max(0.0, result.min_distance));
  }
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
      } else if (e.shape == CollisionElement::Shape::kCylinder) {
        g = std::make_shared<fcl::Cylinderd>(e.radius, e.length);  // exact on both sides
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

void move_pipeline(FclPipeline& p, const RobotModel& m, const double* state) {
  thread_local std::vector<Transform> poses;
  forward_kinematics(m, state, poses);
  for (std::size_t i = 0; i < p.objects.size(); ++i) {
    p.objects[i]->setTransform(test::fcl_transform(poses[p.link[i]] * p.origin[i]));
    p.objects[i]->computeAABB();
  }
  p.manager.update();
}

// ---------------------------------------------------------------------------------- robots

struct Robot {
  std::string name, urdf, srdf;  // file contents (srdf may be empty)
  std::string dir;
};

Robot robot_files(const std::string& name) {
  Robot r{name, "", "", name == "demo" ? test::source_dir() + "/urdf" : test::robots_dir() + "/" + name};
  auto read = [](const std::string& path) {
    std::ifstream in(path);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
  };
  r.urdf = read(name == "demo" ? r.dir + "/demo_arm.urdf" : r.dir + "/robot.urdf");
  if (name != "demo") r.srdf = read(r.dir + "/robot.srdf");
  return r;
}

enum class Matrix { kAdjacent, kSrdf };

CollisionChecker make_checker(const Robot& r, Matrix matrix, const SampledPairs* sampled = nullptr,
                              const CheckerOptions& options = {}) {
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(r.urdf), PackageResolver({r.dir}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  if (matrix == Matrix::kSrdf && !r.srdf.empty()) apply_srdf(parse_srdf(r.srdf, &model), model, acm);
  if (sampled) apply_sampled_pairs(*sampled, acm);
  return CollisionChecker(std::move(model), std::move(acm), options);
}

std::vector<std::vector<double>> random_states(const RobotModel& m, std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> out;
  for (std::size_t i = 0; i < n; ++i) out.push_back(random_configuration(m, rng));
  return out;
}


// ------------------------------------------------------------------ section 1: tolerance

// Boolean self-collision at each tolerance (docs/design.md: "collision" may be answered up
// to `tolerance` apart, never "free" for a colliding state), against the exact distances.
// Meshes as surfaces, as FCL sees them, so that both answer the same question.
void tolerance_section(const Robot& robot, const CollisionChecker& checker, FclPipeline& fcl_pipeline,
                       const std::vector<std::vector<double>>& states, const std::vector<double>& truth,
                       const Sizes& sizes, const std::string& dir) {
  const std::size_t n = states.size();
  const std::size_t t_count = std::size(kTolerancesMm);
  std::vector<std::vector<char>> hits(t_count, std::vector<char>(n));
  std::vector<Query> queries;
  for (std::size_t t = 0; t < t_count; ++t) {
    queries.push_back([&, t](std::size_t i) {
      SelfCollisionRequest request;
      request.solids = false;
      request.tolerance = kTolerancesMm[t] * 1e-3;
      hits[t][i] = checker.check_self(states[i].data(), request).collision;
    });
  }
  std::vector<char> fcl_hits(n);
  queries.push_back([&](std::size_t i) {
    move_pipeline(fcl_pipeline, checker.model(), states[i].data());
    CallbackData data;
    data.pipeline = &fcl_pipeline;
    fcl_pipeline.manager.collide(&data, collision_callback);
    fcl_hits[i] = data.hit;
  });
  const std::vector<Spread> times = timed_runs(n, queries, sizes.runs);
  std::size_t colliding = 0, fcl_disagree = 0;
  for (std::size_t i = 0; i < n; ++i) {
    colliding += truth[i] <= 0.0;
    fcl_disagree += (truth[i] <= 0.0) != static_cast<bool>(fcl_hits[i]);
  }
  Table table("self_tolerance_" + robot.name, robot.name + ": boolean self-collision against tolerance",
              {"tolerance mm", "answered by", "ours us/config", "ours min", "ours max", "FCL us/config", "FCL min", "FCL max",
               "FCL / ours", "false positives %", "largest true distance of a false positive mm", "false negatives"});
  for (std::size_t t = 0; t < t_count; ++t) {
    std::size_t fp = 0, fn = 0;
    double worst = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const bool colliding_truly = truth[i] <= 0.0;
      fn += colliding_truly && !hits[t][i];
      if (hits[t][i] && !colliding_truly) {
        ++fp;
        worst = std::max(worst, truth[i]);
      }
    }
    // Surfaces: the proxies (solids only) never answer here, whatever levels there are.
    std::vector<Table::Cell> row = {kTolerancesMm[t], std::string(t == 0 ? "exact" : "exact (no proxy level for surfaces)")};
    for (const auto& c : Table::cells(times[t])) row.push_back(c);
    for (const auto& c : Table::cells(times.back())) row.push_back(c);
    row.insert(row.end(), {times.back().median / times[t].median, 100.0 * fp / n, worst * 1000, static_cast<double>(fn)});
    table.row(row);
  }
  table.note(std::to_string(n) + " uniform random configurations, " + std::to_string(colliding) + " in collision; " +
             std::to_string(checker.checked_pairs().size()) + " checked link pairs; medians of " +
             std::to_string(sizes.runs) + " runs (min and max beside them). Meshes as surfaces, as FCL sees them; "
             "the exact answer is our distance query at tolerance 0. FCL (exact) disagreed with it on " +
             std::to_string(fcl_disagree) + " configurations.");
  table.write(dir);
}

// ------------------------------------------------------------------- section 2: distance

void distance_section(const Robot& robot, const CollisionChecker& checker, FclPipeline& fcl_pipeline,
                      const std::vector<std::vector<double>>& states, const std::vector<double>& truth,
                      const Sizes& sizes, const std::string& dir) {
  const std::size_t n = std::min(states.size(), sizes.distance_states);
  const std::size_t t_count = std::size(kTolerancesMm);
  std::vector<std::vector<double>> ours(t_count, std::vector<double>(n)), theirs = ours;
  std::vector<Query> queries;
  for (std::size_t t = 0; t < t_count; ++t) {
    queries.push_back([&, t](std::size_t i) {
      SelfCollisionRequest request;
      request.solids = false;
      request.distance = true;
      request.tolerance = kTolerancesMm[t] * 1e-3;
      ours[t][i] = checker.check_self(states[i].data(), request).min_distance;
    });
    queries.push_back([&, t](std::size_t i) {
      move_pipeline(fcl_pipeline, checker.model(), states[i].data());
      CallbackData data;
      data.pipeline = &fcl_pipeline;
      data.distance_request.abs_err = kTolerancesMm[t] * 1e-3;
      fcl_pipeline.manager.distance(&data, distance_callback);
      theirs[t][i] = data.distance;
    });
  }
  // FCL's distance takes up to 20 ms a configuration on pr2: at most three runs here.
  const std::vector<Spread> times = timed_runs(n, queries, std::min<std::size_t>(sizes.runs, 3));
  Table table("self_distance_" + robot.name, robot.name + ": minimum self distance against the allowed error",
              {"allowed error mm", "ours us/config", "ours min", "ours max", "FCL us/config", "FCL min", "FCL max",
               "FCL / ours", "ours largest error mm", "FCL largest error mm", "ours beyond the bound"});
  for (std::size_t t = 0; t < t_count; ++t) {
    double worst_ours = 0.0, worst_fcl = 0.0;
    std::size_t beyond = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double e = ours[t][i] - truth[i];
      worst_ours = std::max(worst_ours, std::abs(e));
      worst_fcl = std::max(worst_fcl, std::abs(theirs[t][i] - truth[i]));
      beyond += e < -1e-12 || e > kTolerancesMm[t] * 1e-3 + 1e-12;
    }
    std::vector<Table::Cell> row = {kTolerancesMm[t]};
    for (const auto& c : Table::cells(times[2 * t])) row.push_back(c);
    for (const auto& c : Table::cells(times[2 * t + 1])) row.push_back(c);
    row.insert(row.end(), {times[2 * t + 1].median / times[2 * t].median, worst_ours * 1000, worst_fcl * 1000,
                           static_cast<double>(beyond)});
    table.row(row);
  }
  table.note(std::to_string(n) + " uniform random configurations; the error is against our exact distance (tolerance 0, "
             "meshes as surfaces). FCL runs with DistanceRequest::abs_err set to the allowed error. Medians of " +
             std::to_string(std::min<std::size_t>(sizes.runs, 3)) + " runs. Ours never reports less than the true distance, nor more than it plus the "
             "allowed error (the last column counts violations).");
  table.write(dir);
}

// ----------------------------------------------- section 5: model only what the scene needs

// The variables a typical request moves: a wrist, or one arm of the PR2.
std::vector<int> moving_group(const RobotModel& m, const std::string& robot, std::string& label) {
  std::vector<std::string> names;
  if (robot == "panda") names = {"panda_joint5", "panda_joint6", "panda_joint7"}, label = "the wrist (joints 5-7)";
  if (robot == "ur5e") names = {"wrist_1_joint", "wrist_2_joint", "wrist_3_joint"}, label = "the wrist (3 joints)";
  if (robot == "pr2") {
    names = {"r_shoulder_pan_joint", "r_shoulder_lift_joint", "r_upper_arm_roll_joint", "r_elbow_flex_joint",
             "r_forearm_roll_joint", "r_wrist_flex_joint", "r_wrist_roll_joint"};
    label = "the right arm (7 joints)";
  }
  if (robot == "demo") names = {"joint5", "joint6"}, label = "the wrist (joints 5-6)";
  std::vector<int> out;
  for (std::size_t v = 0; v < m.variable_count(); ++v) {
    if (std::find(names.begin(), names.end(), m.variable_names()[v]) != names.end()) out.push_back(static_cast<int>(v));
  }
  return out;
}

struct SceneRow {
  std::string setting, compared_with;
  std::size_t pairs;
  Spread time;
  const Spread* base;
  double wrong;  // NaN: not applicable
};

void scene_model_section(const Robot& robot, const std::vector<std::vector<double>>& states, const Sizes& sizes,
                         const std::string& dir) {
  const std::size_t n = states.size();
  const CollisionChecker adjacent = make_checker(robot, Matrix::kAdjacent);
  const CollisionChecker srdf = make_checker(robot, Matrix::kSrdf);
  SamplingOptions sampling;
  sampling.samples = sizes.samples;
  sampling.seed = 7;  // not the test states' seed
  const SampledPairs sampled = sample_collision_pairs(srdf, sampling);
  const CollisionChecker reduced = make_checker(robot, Matrix::kSrdf, &sampled);
  // The moving group: states that differ from a base state only in the group's variables.
  std::string label;
  const std::vector<int> group = moving_group(srdf.model(), robot.name, label);
  const std::vector<std::size_t> moved = srdf.pairs_moved_by(group);
  std::vector<std::vector<double>> group_states;
  std::mt19937_64 rng(13);
  for (std::size_t i = 0; i < n; ++i) {
    auto s = states[i / 10 * 10];  // ten variations of every tenth state
    const auto fresh = random_configuration(srdf.model(), rng);
    for (const int v : group) s[v] = fresh[v];
    group_states.push_back(s);
  }
  SelfCollisionRequest moved_only;
  moved_only.only_pairs = &moved;
  std::vector<char> full_answer(n), srdf_answer(n), reduced_answer(n);
  const std::vector<Spread> t = timed_runs(
      n,
      {[&](std::size_t i) { adjacent.check_self(states[i].data()); },
       [&](std::size_t i) { srdf_answer[i] = srdf.check_self(states[i].data()).collision; },
       [&](std::size_t i) { reduced_answer[i] = reduced.check_self(states[i].data()).collision; },
       [&](std::size_t i) { full_answer[i] = srdf.check_self(group_states[i].data()).collision; },
       [&](std::size_t i) { srdf.check_self(group_states[i].data(), moved_only); }},
      sizes.runs);
  std::size_t missed = 0;
  for (std::size_t i = 0; i < n; ++i) missed += srdf_answer[i] && !reduced_answer[i];
  // The rigid pairs are checked once (their answer cannot change while only the group moves).
  std::vector<std::size_t> rigid;
  for (std::size_t p = 0; p < srdf.checked_pairs().size(); ++p) {
    if (!std::binary_search(moved.begin(), moved.end(), p)) rigid.push_back(p);
  }
  SelfCollisionRequest rigid_only;
  rigid_only.only_pairs = &rigid;
  std::size_t disagree = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const bool split = srdf.check_self(states[i / 10 * 10].data(), rigid_only).collision ||
                       srdf.check_self(group_states[i].data(), moved_only).collision;
    disagree += split != static_cast<bool>(full_answer[i]);
  }
  const double na = std::numeric_limits<double>::quiet_NaN();
  const bool has_srdf = !robot.srdf.empty();
  std::vector<SceneRow> rows = {
      {"adjacent links only", "-", adjacent.checked_pairs().size(), t[0], nullptr, na},
      {has_srdf ? "the SRDF's disabled pairs" : "the SRDF's disabled pairs (no SRDF: same matrix)", "adjacent links only",
       srdf.checked_pairs().size(), t[1], &t[0], na},
      {"sampled never-colliding pairs (" + std::to_string(sampled.samples) + " samples, " +
           std::to_string(sampled.never.size()) + " pairs)",
       "the SRDF's matrix", reduced.checked_pairs().size(), t[2], &t[1], static_cast<double>(missed)},
      {"moving " + label + ": every pair", "-", srdf.checked_pairs().size(), t[3], nullptr, na},
      {"moving " + label + ": only the pairs it moves", "every pair", moved.size(), t[4], &t[3],
       static_cast<double>(disagree)},
  };
  Table table("scene_model_" + robot.name, robot.name + ": modelling only what the scene needs (boolean self-collision)",
              {"setting", "compared with", "checked pairs", "us/config", "min", "max", "saved per query us", "saved %",
               "wrong answers"});
  for (const SceneRow& r : rows) {
    const double saved = r.base ? r.base->median - r.time.median : na;
    table.row({r.setting, r.compared_with, static_cast<double>(r.pairs), r.time.median, r.time.low, r.time.high, saved,
               r.base ? 100.0 * saved / r.base->median : na, r.wrong});
  }
  table.note(std::to_string(n) + " uniform random configurations (the moving-group rows: every tenth of them, with the "
             "group's joints drawn anew ten times); the node's default semantics (closed meshes are solids); medians of " +
             std::to_string(sizes.runs) + " runs. 'Wrong answers': for the sampled pairs (which can hide rare collisions), "
             "configurations the SRDF's matrix finds colliding and the sampled one calls free; for the moved pairs, "
             "configurations where they, with the rigid pairs checked once, answer otherwise than the full check.");
  table.write(dir);
}

// ------------------------------------------------------------------------ other queries

void queries_section(const Robot& robot, const CollisionChecker& checker, const std::vector<std::vector<double>>& states,
                     const Sizes& sizes, const std::string& dir) {
  std::vector<Transform> poses;
  SelfCollisionRequest all, contacts;
  all.all_pairs = true;
  contacts.all_pairs = true;
  contacts.max_contacts = 4;
  const std::vector<Spread> t = timed_runs(
      states.size(),
      {[&](std::size_t i) { forward_kinematics(checker.model(), states[i].data(), poses); },
       [&](std::size_t i) { checker.check_self(states[i].data()); },
       [&](std::size_t i) { checker.check_self(states[i].data(), all); },
       [&](std::size_t i) { checker.check_self(states[i].data(), contacts); }},
      sizes.runs);
  Table table("self_queries_" + robot.name, robot.name + ": other self-collision queries (the node's defaults)",
              {"query", "us/config", "min", "max"});
  const char* names[] = {"forward kinematics alone", "boolean, solids (check_state default)", "all colliding pairs",
                         "all pairs with up to 4 contacts each"};
  for (std::size_t q = 0; q < t.size(); ++q) table.row({names[q], t[q].median, t[q].low, t[q].high});
  table.write(dir);
}

// States near a self contact, on both sides: bisection between a free and a colliding random
// state, keeping the midpoints from the fifth on (the segment is then 1/16 of a random motion,
// a few centimetres at the links, down to micrometres at the last).
std::vector<std::vector<double>> near_contact_states(const CollisionChecker& checker, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto collides = [&](const std::vector<double>& q) { return checker.check_self(q.data()).collision; };
  std::vector<std::vector<double>> out;
  while (out.size() < count) {
    std::vector<double> a = random_configuration(checker.model(), rng), b = random_configuration(checker.model(), rng);
    const bool ca = collides(a);
    if (ca == collides(b)) continue;
    if (ca) std::swap(a, b);  // a free, b colliding
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 24 && out.size() < count; ++k) {
      const double mid = 0.5 * (lo + hi);
      std::vector<double> q(a.size());
      for (std::size_t j = 0; j < a.size(); ++j) q[j] = a[j] + mid * (b[j] - a[j]);
      (collides(q) ? hi : lo) = mid;
      if (k >= 4) out.push_back(std::move(q));
    }
  }
  return out;
}

// Point 4 of the proxies' contract, checked exactly on many states: at each level e, a boolean
// self check at tolerance e (answered by that level) against the exact solid distance: no false
// negative, and no reported collision farther than e.
void proxy_proof_rows(const Robot& robot, const CollisionChecker& checker, std::size_t count, Table& table) {
  const std::vector<std::vector<double>> uniform = random_states(checker.model(), count, 1234);
  const std::vector<std::vector<double>> near = near_contact_states(checker, count, 4321);
  SelfCollisionRequest exact;
  exact.distance = true;
  for (const auto& [kind, states] : {std::pair{"uniform", &uniform}, std::pair{"near_contact", &near}}) {
    std::vector<double> truth(states->size());
    std::size_t colliding = 0;
    for (std::size_t i = 0; i < states->size(); ++i) {
      truth[i] = checker.check_self((*states)[i].data(), exact).min_distance;
      colliding += truth[i] <= 0.0;
    }
    for (const ProxyLevel& level : checker.accelerators().proxy_levels()) {
      std::size_t fn = 0, beyond = 0, fp = 0;
      double farthest = 0.0;
      for (std::size_t i = 0; i < states->size(); ++i) {
        const bool hit = checker.check_self((*states)[i].data(), SelfCollisionRequest{level.level}).collision;
        fn += truth[i] <= 0.0 && !hit;
        if (hit && truth[i] > 0.0) ++fp, farthest = std::max(farthest, truth[i]);
        beyond += hit && truth[i] > level.level;
      }
      table.row({robot.name, level.level * 1000, kind, static_cast<double>(states->size()), static_cast<double>(colliding),
                 static_cast<double>(fn), static_cast<double>(fp), farthest * 1000, static_cast<double>(beyond)});
    }
  }
}

// ------------------------------------------------ section 1b: the speed-against-error curve

// Proxy levels built per robot. The quick run builds the 20 mm level only, on panda and demo.
std::vector<double> proxy_levels_for(const std::string& robot, bool quick) {
  if (quick) return robot == "panda" || robot == "demo" ? std::vector<double>{0.02} : std::vector<double>{};
  if (robot == "pr2") return {0.01, 0.02};  // 28k leaves at 20 mm already (14 open meshes), minutes below
  return {0.002, 0.005, 0.01, 0.02};
}

// Boolean self checks (solids, the node's default) at tolerances 0-20 mm with the proxy levels
// built, one state at a time and as one batch (check_batch: the shared thread pool), against the
// exact solid distances: one row per tolerance and mode of the table speed_error.
void speed_error_rows(const Robot& robot, FclPipeline& fcl_pipeline, const std::vector<std::vector<double>>& states,
                      const Sizes& sizes, bool quick, Table& table, Table& proof) {
  CheckerOptions options;
  options.proxy_levels = proxy_levels_for(robot.name, quick);
  if (options.proxy_levels.empty()) return;
  const CollisionChecker checker = make_checker(robot, Matrix::kSrdf, nullptr, options);
  const std::size_t n = states.size();
  std::vector<double> truth(n);
  SelfCollisionRequest exact;
  exact.distance = true;
  for (std::size_t i = 0; i < n; ++i) truth[i] = checker.check_self(states[i].data(), exact).min_distance;
  std::vector<double> flat;
  for (const auto& s : states) flat.insert(flat.end(), s.begin(), s.end());
  const double tolerances_mm[] = {0, 2, 5, 10, 20};
  std::vector<std::vector<char>> single(std::size(tolerances_mm), std::vector<char>(n)), batch(std::size(tolerances_mm));
  std::vector<Query> queries;
  for (std::size_t t = 0; t < std::size(tolerances_mm); ++t) {
    queries.push_back([&, t](std::size_t i) {
      single[t][i] = checker.check_self(states[i].data(), SelfCollisionRequest{tolerances_mm[t] * 1e-3}).collision;
    });
  }
  queries.push_back([&](std::size_t i) {
    move_pipeline(fcl_pipeline, checker.model(), states[i].data());
    CallbackData data;
    data.pipeline = &fcl_pipeline;
    fcl_pipeline.manager.collide(&data, collision_callback);
  });
  const std::vector<Spread> times = timed_runs(n, queries, sizes.runs);
  for (std::size_t t = 0; t < std::size(tolerances_mm); ++t) {
    std::vector<double> runs;
    for (std::size_t r = 0; r < sizes.runs; ++r) {
      runs.push_back(bench::us_per_item(n, [&] {
        const std::vector<bool> hits = checker.check_self_batch(flat.data(), n, tolerances_mm[t] * 1e-3);
        batch[t].assign(hits.begin(), hits.end());
      }));
    }
    const Spread batch_time = bench::spread(runs);
    const ProxyLevel* level = checker.accelerators().proxies_for(tolerances_mm[t] * 1e-3);
    for (const auto& [mode, hits, time] : {std::tuple{"single", &single[t], times[t]}, std::tuple{"batch", &batch[t], batch_time}}) {
      const bench::AnswerErrors e = bench::answer_errors(*hits, truth);
      table.row({robot.name, "self", tolerances_mm[t], mode, time.median, time.low, time.high, 100.0 * e.false_positives / n,
                 static_cast<double>(e.false_negatives), e.farthest_false_positive * 1000, times.back().median, level ? level->level * 1000 : 0.0,
                 level ? static_cast<double>(level->leaves) : 0.0, level ? level->build_seconds : 0.0});
    }
  }
  proxy_proof_rows(robot, checker, quick ? 60 : 10000, proof);
}

void run_robot(const std::string& name, const Sizes& sizes, const std::string& dir, bool quick, Table& speed_error,
               Table& proof) {
  const Robot robot = robot_files(name);
  const CollisionChecker checker = make_checker(robot, Matrix::kSrdf);
  FclPipeline fcl_pipeline;
  build_pipeline(checker.model(), checker.acm(), fcl_pipeline);
  const auto states = random_states(checker.model(), sizes.states, 99);
  std::vector<double> truth(states.size());
  SelfCollisionRequest exact;
  exact.solids = false;
  exact.distance = true;
  for (std::size_t i = 0; i < states.size(); ++i) truth[i] = checker.check_self(states[i].data(), exact).min_distance;
  std::cout << "\n## " << name << "\n";
  tolerance_section(robot, checker, fcl_pipeline, states, truth, sizes, dir);
  distance_section(robot, checker, fcl_pipeline, states, truth, sizes, dir);
  scene_model_section(robot, states, sizes, dir);
  queries_section(robot, checker, states, sizes, dir);
  speed_error_rows(robot, fcl_pipeline, states, sizes, quick, speed_error, proof);
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  const bool quick = bench::quick_mode(argc, argv);
  const Sizes sizes = quick ? Sizes{60, 10, 2, 300} : Sizes{5000, 300, 5, 10000};
  std::cout << "# Self-collision per configuration, against FCL as MoveIt uses it\n# Machine: "
            << bench::machine_description() << "\n";
  Table speed_error("speed_error", "Boolean self-collision (solids): time per state against tolerance, with the link proxies",
                    {"robot", "scene", "tolerance_mm", "mode", "us_per_state", "us_per_state min", "us_per_state max", "false_positive_pct", "false_negatives",
                     "farthest_false_positive_mm", "fcl_exact_us_per_state", "proxy_level_mm", "proxy_leaves",
                     "proxy_build_s"});
  Table proof("proxy_proof", "The proxies' contract on many states: each level at tolerance = level against exact solid distances",
              {"robot", "level mm", "states", "count", "colliding", "false negatives", "false positives",
               "farthest false positive mm", "beyond the tolerance"});
  for (const char* robot : {"panda", "ur5e", "pr2", "demo"}) {
    run_robot(robot, sizes, bench::output_dir(argc, argv), quick, speed_error, proof);
  }
  proof.note("Uniform random states and states from centimetres down to micrometres of a self contact on both sides (bisection between a "
             "free and a colliding state), SRDF matrix, padding 0. A false negative (a colliding state answered free) "
             "or a reported collision farther than the tolerance would break docs/design.md; both must be 0.");
  proof.write(bench::output_dir(argc, argv));
  speed_error.note("Uniform random states (the same as section 1), SRDF matrix, solids; the truth is our exact solid "
                   "distance. Tolerance 0 is the exact check; at tolerance t the coarsest proxy level e <= t answers "
                   "the pairs its build measured it not slower on, the exact test the others (narrowphase/link_proxy.h, "
                   "model/proxy_calibration.h; proxy_level_mm 0: none, exact). Both modes skip the self pairs whose proven "
                   "clearance grid clears the padding (model/pair_clearance.h). batch: check_batch over all states on "
                   "the shared thread pool (" + std::to_string(ThreadPool::shared().capacity()) +
                   " threads); at a tolerance a proxy level fits, four states at a time in SIMD lanes (model/proxy_batch.h, " +
                   (avx2_available() ? "AVX2, four lanes" : "SSE2, two lanes: this CPU has no AVX2") +
                   "). FCL: exact, surfaces, one state at a time. The scene "
                   "`octree` rows are bench_environment's (table speed_error_octree), merged in by the report.");
  speed_error.write(bench::output_dir(argc, argv));
  return 0;
}
