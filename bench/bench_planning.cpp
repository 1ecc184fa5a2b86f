// Planning at planner rates (report table `planning`): OMPL's RRTConnect on panda among generated
// MoveIt-style scenes (test/planning_scenes.h: tables, shelves, open boxes, cages, clutter; 20-60
// primitives each), start and goal free on the exact geometry, a third of the goals within 5 mm
// of an obstacle. Three checkers plan the same problems in the same run:
//   - ours exact (tolerance 0) and ours at 10 mm (proxy levels 5/10/20 mm), through
//     planning/ompl_validity.h (certified motions);
//   - FCL as MoveIt sets it up: BVHModel<OBBRSS> per link mesh, primitive shapes for the objects
//     in a dynamic AABB tree, the SRDF's allowed pairs; OMPL's DiscreteMotionValidator at 1 % of
//     the space's extent.
// Every returned path is re-checked, segment by segment, by our general certified check_motion
// at tolerance 0 (not the planning path: another code path) and by FCL at every 1e-3 rad along
// it; a path either finds colliding counts against its checker. The scenes are written as
// MoveIt `.scene` text (build/bench/scenes) with the problems (problems.json).
#include <fcl/fcl.h>

#include <ompl/base/DiscreteMotionValidator.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <fstream>
#include <random>

#include "bench_util.h"
#include "checker_fixtures.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/planning/ompl_validity.h"
#include "bvh_collision/robot/robot_description.h"
#include "fcl_oracle.h"
#include "planning_scenes.h"
#include "advancement_oracle.h"

namespace bvh_collision {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using bench::Table;

const std::vector<std::string> kArm = {"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                       "panda_joint5", "panda_joint6", "panda_joint7"};

CollisionChecker load_panda(const std::string& cache, double& build_seconds) {
  CheckerOptions options;
  options.proxy_levels = {0.005, 0.01, 0.02};
  options.proxy_cache = cache;
  const auto start = std::chrono::steady_clock::now();
  CollisionChecker checker = test::panda_as_moveit(options);
  build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return checker;
}

// ---- FCL as MoveIt uses it -------------------------------------------------------------------

// The links' OBBRSS models, built once for every scene.
using FclLinkModels = std::vector<std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>>;
FclLinkModels fcl_link_models(const RobotModel& model) {
  FclLinkModels out;
  for (const RobotLink& link : model.links()) {
    for (const CollisionElement& e : link.collision) out.push_back(test::fcl_model<fcl::OBBRSSd>(*e.mesh));
  }
  return out;
}

class FclPanda {
 public:
  FclPanda(const CollisionChecker& checker, const FclLinkModels& models, const test::PlanningScene& scene) : checker_(checker) {
    const RobotModel& model = checker.model();
    std::size_t k = 0;
    for (std::size_t l = 0; l < model.links().size(); ++l) {
      for (const CollisionElement& e : model.links()[l].collision) {
        links_.push_back({static_cast<int>(l), e.origin, std::make_unique<fcl::CollisionObjectd>(models[k++])});
      }
    }
    for (const SceneObject& o : scene.objects) {
      for (const SceneShape& s : o.shapes) world_.push_back(std::make_unique<fcl::CollisionObjectd>(geometry(s.shape), test::fcl_transform(o.pose * s.pose)));
    }
    for (auto& w : world_) {
      w->computeAABB();
      manager_.registerObject(w.get());
    }
    manager_.setup();
  }

  bool collides(const double* state) {
    forward_kinematics(checker_.model(), state, poses_);
    for (LinkObject& l : links_) {
      l.object->setTransform(test::fcl_transform(poses_[l.link] * l.origin));
      l.object->computeAABB();
    }
    for (const auto& [a, b] : checker_.checked_pairs()) {
      for (const LinkObject& la : links_) {
        if (la.link != a) continue;
        for (const LinkObject& lb : links_) {
          if (lb.link != b) continue;
          fcl::CollisionRequestd request;
          fcl::CollisionResultd result;
          if (fcl::collide(la.object.get(), lb.object.get(), request, result) > 0) return true;
        }
      }
    }
    for (LinkObject& l : links_) {
      fcl::DefaultCollisionData<double> data;
      manager_.collide(l.object.get(), &data, fcl::DefaultCollisionFunction<double>);
      if (data.result.isCollision()) return true;
    }
    return false;
  }

 private:
  static std::shared_ptr<fcl::CollisionGeometryd> geometry(const ObjectShape& s) {
    switch (s.kind) {
      case ObjectShape::Kind::kBox: return std::make_shared<fcl::Boxd>(s.size.x(), s.size.y(), s.size.z());
      case ObjectShape::Kind::kSphere: return std::make_shared<fcl::Sphered>(s.radius);
      case ObjectShape::Kind::kCylinder: return std::make_shared<fcl::Cylinderd>(s.radius, s.length);
      default: throw std::logic_error("the scene generator makes boxes, spheres and cylinders only");
    }
  }
  struct LinkObject {
    int link;
    Transform origin;
    std::unique_ptr<fcl::CollisionObjectd> object;
  };
  const CollisionChecker& checker_;
  std::vector<LinkObject> links_;
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> world_;
  fcl::DynamicAABBTreeCollisionManagerd manager_;
  std::vector<Transform> poses_;
};

// ---- Timing wrappers: every call timed on its own, for medians ------------------------------------

struct CallTimes {
  std::vector<double> states, motions;  // microseconds per call
};

double now_us() {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

class TimedValidity : public ob::StateValidityChecker {
 public:
  TimedValidity(const ob::SpaceInformationPtr& si, std::function<bool(const ob::State*)> valid, CallTimes* times)
      : ob::StateValidityChecker(si), valid_(std::move(valid)), times_(times) {}
  bool isValid(const ob::State* s) const override {
    const double t0 = now_us();
    const bool v = valid_(s);
    times_->states.push_back(now_us() - t0);
    return v;
  }

 private:
  std::function<bool(const ob::State*)> valid_;
  CallTimes* times_;
};

class TimedMotions : public ob::MotionValidator {
 public:
  TimedMotions(const ob::SpaceInformationPtr& si, std::shared_ptr<ob::MotionValidator> inner, CallTimes* times)
      : ob::MotionValidator(si), inner_(std::move(inner)), times_(times) {}
  bool checkMotion(const ob::State* a, const ob::State* b) const override {
    const double t0 = now_us();
    const bool v = inner_->checkMotion(a, b);
    times_->motions.push_back(now_us() - t0);
    return v;
  }
  bool checkMotion(const ob::State* a, const ob::State* b, std::pair<ob::State*, double>& last) const override {
    const double t0 = now_us();
    const bool v = inner_->checkMotion(a, b, last);
    times_->motions.push_back(now_us() - t0);
    return v;
  }

 private:
  std::shared_ptr<ob::MotionValidator> inner_;
  CallTimes* times_;
};

// ---- Problems ----------------------------------------------------------------------------------

struct Problem {
  int scene = 0;
  std::vector<double> start, goal;  // full states
  bool near = false;                // the goal within 5 mm of an obstacle
  double goal_clearance = 0.0;
};

std::vector<double> with_arm(const std::vector<double>& base, const std::vector<int>& arm, std::mt19937_64& rng,
                             const planning::JointGroup& group) {
  std::vector<double> q = base;
  for (std::size_t i = 0; i < arm.size(); ++i) q[arm[i]] = std::uniform_real_distribution<double>(group.lower[i], group.upper[i])(rng);
  return q;
}

double exact_clearance(const CollisionChecker& checker, const double* q, const Environment& env) {
  SelfCollisionRequest self;
  self.distance = true;
  EnvironmentRequest request;
  request.distance = true;
  request.contacts = false;
  const SelfCollisionResult s = checker.check_self(q, self);
  const EnvironmentResult e = checker.check_environment(q, env, request);
  return s.collision || e.collision ? 0.0 : std::min(s.min_distance, e.min_distance);
}

// A free goal moved towards a colliding state until it lies within 5 mm of a collision.
bool near_goal(const SceneChecker& scene, std::vector<double>& goal, const std::vector<double>& colliding) {
  std::vector<double> lo = goal, hi = colliding, mid(goal.size());
  for (int k = 0; k < 60; ++k) {
    for (std::size_t j = 0; j < mid.size(); ++j) mid[j] = 0.5 * (lo[j] + hi[j]);
    (scene.collides(mid.data()) ? hi : lo) = mid;
    if (exact_clearance(scene.checker(), lo.data(), scene.environment()) < 0.005) break;
  }
  goal = lo;
  return exact_clearance(scene.checker(), lo.data(), scene.environment()) < 0.005;
}

Problem make_problem(const SceneChecker& scene, int index, std::mt19937_64& rng, const planning::JointGroup& group,
                     const std::vector<int>& arm, const std::vector<double>& base) {
  Problem p;
  p.scene = index;
  auto free_state = [&] {
    for (;;) {
      std::vector<double> q = with_arm(base, arm, rng, group);
      if (!scene.collides(q.data())) return q;
    }
  };
  p.start = free_state();
  // A goal the straight motion cannot reach (planning is needed) when one is found.
  for (int tries = 0; tries < 200; ++tries) {
    p.goal = free_state();
    if (!scene.check_motion(p.start.data(), p.goal.data()).valid) break;
  }
  if (index % 3 == 2) {
    for (int tries = 0; tries < 50 && !p.near; ++tries) {
      std::vector<double> goal = p.goal, c = with_arm(base, arm, rng, group);
      if (!scene.collides(c.data())) continue;
      if (near_goal(scene, goal, c)) p.goal = goal, p.near = true;
    }
  }
  p.goal_clearance = exact_clearance(scene.checker(), p.goal.data(), scene.environment());
  return p;
}

// ---- Planning and re-checking ---------------------------------------------------------------------

struct Run {
  bool solved = false;
  double seconds = 0.0;
  std::vector<std::vector<double>> path;  // full states
};

Run plan(og::SimpleSetup& setup, const planning::CheckerPlanningContext& layout, const Problem& p, double limit) {
  ob::ScopedState<> start(setup.getStateSpace()), goal(setup.getStateSpace());
  const auto& names = layout.group.names;
  const auto& all = layout.checker.model().variable_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto j = static_cast<std::size_t>(std::find(all.begin(), all.end(), names[i]) - all.begin());
    start[i] = p.start[j], goal[i] = p.goal[j];
  }
  setup.clear();
  setup.setStartAndGoalStates(start, goal);
  Run run;
  const auto t0 = std::chrono::steady_clock::now();
  // A time limit checked by the planner itself, as MoveIt's planning context gives it: OMPL's
  // solve(seconds) checks the clock from a thread of its own (for limits of a second or more)
  // that wakes every millisecond, and its join took 1.0 ms of the median plan (3.5 ms at 10 mm,
  // when 0.3 ms were checks), whatever the checker.
  run.solved = setup.solve(ob::timedPlannerTerminationCondition(limit)) == ob::PlannerStatus::EXACT_SOLUTION;
  if (run.solved) setup.simplifySolution();
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!run.solved) return run;
  const og::PathGeometric& path = setup.getSolutionPath();
  for (std::size_t w = 0; w < path.getStateCount(); ++w) run.path.push_back(layout.full_state(path.getState(w)));
  return run;
}

// Does any segment collide: by conservative advancement with exact distances (test/advancement_oracle.h,
// written apart from the engine that planned), and by FCL every 1e-3 rad?
std::pair<bool, bool> path_collides(const Run& run, const CollisionChecker& checker, const Environment& env, FclPanda& fcl) {
  bool ours = false, theirs = false;
  for (std::size_t w = 0; w + 1 < run.path.size(); ++w) {
    const std::vector<double>& a = run.path[w];
    const std::vector<double>& b = run.path[w + 1];
    MotionRequest exact;
    exact.max_states = 200000;
    ours = ours || !test::advancement_motion(checker, a.data(), b.data(), env, exact).valid;
    double longest = 0.0;
    for (std::size_t j = 0; j < a.size(); ++j) longest = std::max(longest, std::abs(b[j] - a[j]));
    const int steps = std::max(1, static_cast<int>(std::ceil(longest / 1e-3)));
    std::vector<double> q(a.size());
    for (int k = 0; k <= steps && !theirs; ++k) {
      for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * k / steps;
      theirs = fcl.collides(q.data());
    }
  }
  return {ours, theirs};
}

struct Tally {
  std::string name;
  int solved = 0, ours_colliding = 0, fcl_colliding = 0;
  std::vector<double> seconds;  // every problem (an unsolved one at the limit)
  CallTimes calls;
};

// A run's figures into its checker's tally: its time (an unsolved one at the limit) and, solved,
// whether its path collides by either re-check.
void record(Tally& tally, const Run& run, double limit, const CollisionChecker& checker, const Environment& env, FclPanda& fcl) {
  tally.seconds.push_back(run.solved ? run.seconds : limit);
  if (!run.solved) return;
  ++tally.solved;
  const auto [ours, theirs] = path_collides(run, checker, env, fcl);
  tally.ours_colliding += ours;
  tally.fcl_colliding += theirs;
}

// One problem planned by one of our configurations (tolerance 0 or 10 mm).
void plan_ours(Tally& tally, const CollisionChecker& checker, const std::shared_ptr<const Environment>& env,
               const planning::JointGroup& group, const Problem& p, double tolerance, double limit, FclPanda& fcl) {
  auto context = std::make_shared<planning::CheckerPlanningContext>(checker, env, group, p.start);
  context->tolerance = tolerance;
  context->scene();  // the object grid: built before the clock starts, as FCL's tree is
  og::SimpleSetup setup(group.make_space());
  const auto si = setup.getSpaceInformation();
  auto states = std::make_shared<planning::CheckerStateValidityChecker>(si, context);
  setup.setStateValidityChecker(std::make_shared<TimedValidity>(si, [states](const ob::State* s) { return states->isValid(s); }, &tally.calls));
  si->setMotionValidator(std::make_shared<TimedMotions>(si, std::make_shared<planning::CheckerMotionValidator>(si, context), &tally.calls));
  setup.setPlanner(std::make_shared<og::RRTConnect>(si));
  setup.setup();
  const std::size_t states0 = tally.calls.states.size(), motions0 = tally.calls.motions.size();
  const Run run = plan(setup, *context, p, limit);
  if (std::getenv("BENCH_PLANNING_VERBOSE")) {
    double in_states = 0, in_motions = 0;
    for (std::size_t i = states0; i < tally.calls.states.size(); ++i) in_states += tally.calls.states[i];
    for (std::size_t i = motions0; i < tally.calls.motions.size(); ++i) in_motions += tally.calls.motions[i];
    const std::vector<double> motions(tally.calls.motions.begin() + static_cast<std::ptrdiff_t>(motions0), tally.calls.motions.end());
    std::printf("  %s: %s in %.1f ms; %zu states (%.1f ms), %zu motions (%.1f ms; us median %.0f, p90 %.0f, max %.0f)\n",
                tally.name.c_str(), run.solved ? "solved" : "failed", 1e3 * run.seconds, tally.calls.states.size() - states0,
                in_states / 1e3, motions.size(), in_motions / 1e3, bench::median(motions), bench::percentile(motions, 0.9),
                motions.empty() ? 0.0 : *std::max_element(motions.begin(), motions.end()));
  }
  record(tally, run, limit, checker, *env, fcl);
}

void plan_fcl(Tally& tally, const CollisionChecker& checker, const std::shared_ptr<const Environment>& env,
              const planning::JointGroup& group, const Problem& p, double limit, FclPanda& fcl) {
  // The context only lays out states (group values into the full state); FCL answers.
  auto layout = std::make_shared<planning::CheckerPlanningContext>(checker, env, group, p.start);
  og::SimpleSetup setup(group.make_space());
  const auto si = setup.getSpaceInformation();
  setup.setStateValidityChecker(std::make_shared<TimedValidity>(si, [layout, &fcl](const ob::State* s) {
    thread_local std::vector<double> q;
    layout->full_state(s, q);
    return !fcl.collides(q.data());
  }, &tally.calls));
  si->setStateValidityCheckingResolution(0.01);  // MoveIt's default: 1 % of the space's extent
  si->setMotionValidator(std::make_shared<TimedMotions>(si, std::make_shared<ob::DiscreteMotionValidator>(si), &tally.calls));
  setup.setPlanner(std::make_shared<og::RRTConnect>(si));
  setup.setup();
  const Run run = plan(setup, *layout, p, limit);
  record(tally, run, limit, checker, *env, fcl);
}

void write_problems(const std::string& dir, const std::vector<Problem>& problems, std::uint64_t seed) {
  std::filesystem::create_directories(dir);
  nlohmann::json out = nlohmann::json::array();
  for (const Problem& p : problems) {
    std::ofstream scene(dir + "/panda_scene_" + std::to_string(p.scene) + ".scene");
    write_scene_text(test::generate_scene(seed, p.scene), scene);
    out.push_back({{"scene", "panda_scene_" + std::to_string(p.scene) + ".scene"}, {"start", p.start}, {"goal", p.goal},
                   {"goal_within_5mm", p.near}, {"goal_clearance", p.goal_clearance}});
  }
  std::ofstream(dir + "/problems.json") << out.dump(1) << "\n";
}

void report(const std::string& out_dir, const std::vector<Tally>& tallies, std::size_t problems, std::size_t near,
            double limit, double build_seconds) {
  Table table("planning", "Planning with RRTConnect on panda among generated MoveIt-style scenes",
              {"checker", "solved", "median plan ms", "p95 plan ms", "per state check us (median)",
               "per motion check us (median)", "paths colliding (our exact certified re-check)",
               "paths colliding (FCL every 1e-3 rad)"});
  for (const Tally& t : tallies) {
    table.row({t.name, static_cast<double>(t.solved), 1e3 * bench::median(t.seconds), 1e3 * bench::percentile(t.seconds, 0.95),
               bench::median(t.calls.states), bench::median(t.calls.motions), static_cast<double>(t.ours_colliding),
               static_cast<double>(t.fcl_colliding)});
  }
  table.note(std::to_string(problems) + " problems (" + std::to_string(near) + " goals within 5 mm of an obstacle), one scene each "
             "(20-60 boxes, cylinders and spheres: tables, shelves, open boxes, cages, clutter), panda's 7 arm joints, the SRDF's "
             "allowed pairs; " + bench::format(limit) + " s a problem, then OMPL's path simplifier on the same validators; "
             "plan times count unsolved problems at the limit. Per-check figures are medians over every call the planners made "
             "(each call timed on its own). Ours: planning/ompl_validity.h (SceneChecker, certified motions), proxy levels "
             "5, 10 and 20 mm (" + bench::format(build_seconds) + " s to build or read from the cache). FCL: BVHModel<OBBRSS> "
             "links, primitive objects in a dynamic AABB tree, OMPL's DiscreteMotionValidator at 1 %. Scenes and problems: "
             "build/bench/scenes (MoveIt .scene text, problems.json).");
  table.write(out_dir);
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  const std::string out_dir = bench::output_dir(argc, argv);
  const bool quick = bench::quick_mode(argc, argv);
  const int count = quick ? 3 : 100;
  const double limit = quick ? 2.0 : 10.0;
  const std::uint64_t seed = 2026;
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  ompl::RNG::setSeed(1);
  double build_seconds = 0.0;
  const CollisionChecker checker = load_panda(out_dir + "/../proxy_cache", build_seconds);
  const planning::JointGroup group = planning::JointGroup::of(checker.model(), kArm);
  std::vector<int> arm;
  for (const std::string& name : kArm) {
    const auto& all = checker.model().variable_names();
    arm.push_back(static_cast<int>(std::find(all.begin(), all.end(), name) - all.begin()));
  }
  std::vector<double> base(checker.model().variable_count(), 0.02);  // the fingers half open
  const FclLinkModels fcl_models = fcl_link_models(checker.model());
  std::mt19937_64 rng(seed);
  std::vector<Problem> problems;
  std::vector<Tally> tallies(3);
  tallies[0].name = "ours, exact (tolerance 0)";
  tallies[1].name = "ours, 10 mm";
  tallies[2].name = "FCL + discrete motions at 1 %";
  std::size_t near = 0;
  // BENCH_PLANNING_CHECKERS=01 (say): only those rows (0 ours exact, 1 ours 10 mm, 2 FCL), to profile one.
  const char* only = std::getenv("BENCH_PLANNING_CHECKERS");
  const auto runs = [&](char row) { return only == nullptr || std::string(only).find(row) != std::string::npos; };
  for (int k = 0; k < count; ++k) {
    const test::PlanningScene scene = test::generate_scene(seed, k);
    const auto env = std::make_shared<const Environment>(scene.environment());
    const SceneChecker exact(checker, env);
    const Problem p = make_problem(exact, k, rng, group, arm, base);
    problems.push_back(p);
    near += p.near;
    FclPanda fcl(checker, fcl_models, scene);
    if (runs('0')) plan_ours(tallies[0], checker, env, group, p, 0.0, limit, fcl);
    if (runs('1')) plan_ours(tallies[1], checker, env, group, p, 0.01, limit, fcl);
    if (runs('2')) plan_fcl(tallies[2], checker, env, group, p, limit, fcl);
    std::printf("problem %d (%zu shapes%s): solved %d/%d/%d so far\n", k, scene.shape_count(), p.near ? ", goal near" : "",
                tallies[0].solved, tallies[1].solved, tallies[2].solved);
    std::fflush(stdout);
  }
  write_problems(out_dir + "/scenes", problems, seed);
  report(out_dir, tallies, problems.size(), near, limit, build_seconds);
  return 0;
}
