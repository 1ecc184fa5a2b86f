// Planning at planner rates (report table `planning`): OMPL's RRTConnect on several robots among
// generated MoveIt-style scenes, start and goal free on the exact geometry, a third of the goals
// within 5 mm of an obstacle, goals drawn towards a point inside a fixture where the scene has one:
//   - panda (7 joints): tables, shelves, open boxes, cages, clutter (test/planning_scenes.h
//     generate_scene) and, every other problem, a harder fixture to reach into (hard_scene: a shelf
//     of thin boards, a dense cage of thin bars, a drawer);
//   - ur5e (6 joints): the first kind of scene;
//   - pr2 with both arms at once (14 joints) and pr2's torso lift with its right arm (8 joints, the
//     left arm tucked): a table with a cabinet between the arms, shelves on each side (pr2_scene).
// Three checkers plan the same problems in the same run:
//   - ours exact (tolerance 0) and ours at 10 mm (the node's proxy levels), through
//     planning/ompl_validity.h (certified motions);
//   - FCL as MoveIt sets it up: BVHModel<OBBRSS> per link mesh, primitive shapes for the objects
//     in a dynamic AABB tree, the SRDF's allowed pairs; OMPL's DiscreteMotionValidator at 1 % of
//     the space's extent.
// Every returned path is re-checked, segment by segment, by conservative advancement with exact
// distances (test/advancement_oracle.h: not the planning path) and by FCL at every 1e-3 rad along
// it; a path either finds colliding counts against its checker. The scenes are written as
// MoveIt `.scene` text (build/bench/scenes) with the problems (problems.json).
// BENCH_PLANNING_ROBOTS=panda,pr2_both_arms (say) plans only those robots; BENCH_PLANNING_PROBLEMS=N sets
// the problems per robot; BENCH_PLANNING_CHECKERS=01 only those rows (0 ours exact, 1 ours 10 mm,
// 2 FCL), to profile one; BENCH_PLANNING_OMPL_SEED=N another seed for OMPL (1 by default).
// BENCH_PLANNING_LOG=file writes every state and motion call our rows make (full states, in order);
// BENCH_PLANNING_REPLAY=file then asks a checker the same calls on the same problems instead of
// planning (function replay_calls, for callgrind: two builds compared on the same calls, where
// changed answers would otherwise change the plans), and prints what they answered;
// BENCH_PLANNING_REPLAY_REPEAT=N replays each problem's calls N times and adds its fastest time.
// BENCH_PLANNING_MOTIONS_AT_TOLERANCE=N: our searches go on exact after N motions unsolved
// (planning::solve_tolerance_first; kMotionsAtTolerance by default).
#include <fcl/fcl.h>

#include <ompl/base/DiscreteMotionValidator.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/ScopedState.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <functional>
#include <map>
#include <optional>
#include <random>

#include "bench_util.h"
#include "planning_times.h"
#include "checker_fixtures.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/planning/ompl_validity.h"
#include "bvh_collision/robot/robot_description.h"
#include "fcl_oracle.h"
#include "fcl_planning_robot.h"
#include "planning_calls.h"
#include "planning_scenes.h"
#include "advancement_oracle.h"

namespace bvh_collision {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;
using bench::Table;
using bench::CallMark;
using bench::CallTimes;
using bench::ProblemTimes;
using bench::TimedMotions;
using bench::TimedValidity;

// A robot of the benchmark: its planning group, where the other joints stand, its scenes.
struct PlanningRobot {
  std::string name;                        // the table's robot column
  std::string folder;                      // ../shared/robots/<folder>, loaded as MoveIt does
  std::vector<std::string> group;          // the planned joints
  std::map<std::string, double> base;      // the other joints' values (0 when not named)
  std::vector<double> proxy_levels;        // what the node builds within its sphere budget
  std::string tip;                         // the link a goal is drawn towards the scene's target
  // Scene `index`; sets `target` (world) when goals should be drawn towards it.
  std::function<test::PlanningScene(std::uint64_t, int, std::optional<Vec3>&)> scene;
};

std::vector<std::string> arm(const std::string& prefix) {
  std::vector<std::string> out;
  for (const char* j : {"shoulder_pan", "shoulder_lift", "upper_arm_roll", "elbow_flex", "forearm_roll", "wrist_flex", "wrist_roll"}) {
    out.push_back(prefix + j + "_joint");
  }
  return out;
}

std::vector<PlanningRobot> planning_robots() {
  auto pr2_scenes = [](std::uint64_t seed, int k, std::optional<Vec3>& target) {
    Vec3 t;
    test::PlanningScene s = test::pr2_scene(seed, k, &t);
    target = t;
    return s;
  };
  std::vector<PlanningRobot> out;
  out.push_back({"panda", "panda", {}, {{"panda_finger_joint1", 0.02}}, {0.005, 0.01, 0.02},
                 "panda_hand", [](std::uint64_t seed, int k, std::optional<Vec3>& target) {
                   if (k % 2 == 0) return test::generate_scene(seed, k);
                   Vec3 t;
                   test::PlanningScene s = test::hard_scene(seed, k, &t);
                   target = t;
                   return s;
                 }});
  for (int j = 1; j <= 7; ++j) out.back().group.push_back("panda_joint" + std::to_string(j));
  out.push_back({"ur5e", "ur5e", {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint", "wrist_3_joint"},
                 {}, {0.005, 0.01, 0.02}, "wrist_3_link",
                 [](std::uint64_t seed, int k, std::optional<Vec3>&) { return test::generate_scene(seed, k); }});
  std::vector<std::string> both = arm("r_");
  for (const std::string& j : arm("l_")) both.push_back(j);
  out.push_back({"pr2 both arms", "pr2", both, {{"torso_lift_joint", 0.15}}, {0.005, 0.01, 0.02}, "r_gripper_palm_link", pr2_scenes});
  std::vector<std::string> torso_arm = {"torso_lift_joint"};
  for (const std::string& j : arm("r_")) torso_arm.push_back(j);
  // The left arm tucked beside the body, as pr2's tuck_arms leaves it.
  const std::map<std::string, double> tucked = {{"l_shoulder_pan_joint", 0.06}, {"l_shoulder_lift_joint", 1.25}, {"l_upper_arm_roll_joint", 1.79},
                                                {"l_elbow_flex_joint", -1.68}, {"l_forearm_roll_joint", -1.73}, {"l_wrist_flex_joint", -0.1},
                                                {"l_wrist_roll_joint", -0.09}};
  out.push_back({"pr2 torso + right arm", "pr2", torso_arm, tucked, {0.005, 0.01, 0.02}, "r_gripper_palm_link", pr2_scenes});
  return out;
}

CollisionChecker load_robot(const PlanningRobot& robot, const std::string& cache, double& build_seconds) {
  CheckerOptions options;
  options.proxy_levels = robot.proxy_levels;
  options.proxy_cache = cache;
  const auto start = std::chrono::steady_clock::now();
  CollisionChecker checker = test::load_as_moveit(robot.folder, options);
  build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return checker;
}

// ---- Timing wrappers (planning_times.h), the call log and its replay -------------------------

bench::CallLog call_log;         // BENCH_PLANNING_LOG
bench::LoggedCalls logged_calls;  // BENCH_PLANNING_REPLAY

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

// Where a problem's states come from: the group's variables, the rest at `base`, and a point
// goals are drawn towards (the tip link's origin nearest it) when the scene has one.
struct ProblemSpace {
  const planning::JointGroup& group;
  std::vector<int> arm;      // the group's variables in the full state
  std::vector<double> base;  // the full state's other values
  std::optional<Vec3> target;
  int tip = -1;              // link index
};

// A goal near the target when there is one (the nearest of 200 free draws, preferring those the
// straight motion from the start cannot reach), else a free draw the straight motion cannot reach
// when one is found.
std::vector<double> pick_goal(const SceneChecker& scene, const ProblemSpace& space, const std::vector<double>& start,
                              const std::function<std::vector<double>()>& free_state) {
  std::vector<double> best;
  double best_score = std::numeric_limits<double>::infinity();
  std::vector<Transform> poses;
  for (int tries = 0; tries < 200; ++tries) {
    std::vector<double> q = free_state();
    const bool needs_planning = !scene.check_motion(start.data(), q.data()).valid;
    if (!space.target) {
      if (needs_planning || tries == 199) return q;
      continue;
    }
    forward_kinematics(scene.checker().model(), q.data(), poses);
    const double score = (poses[space.tip].t - *space.target).norm() + (needs_planning ? 0.0 : 10.0);
    if (score < best_score) best_score = score, best = std::move(q);
  }
  return best;
}

Problem make_problem(const SceneChecker& scene, int index, std::mt19937_64& rng, const ProblemSpace& space) {
  Problem p;
  p.scene = index;
  auto free_state = [&] {
    for (int tries = 0; tries < 1000000; ++tries) {
      std::vector<double> q = with_arm(space.base, space.arm, rng, space.group);
      if (!scene.collides(q.data())) return q;
    }
    throw std::runtime_error("no free state in a million draws: the robot's base state collides");
  };
  p.start = free_state();
  p.goal = pick_goal(scene, space, p.start, free_state);
  if (index % 3 == 2) {
    for (int tries = 0; tries < 50 && !p.near; ++tries) {
      // A colliding state near the goal (within 0.4 rad a joint), the goal moved towards it.
      std::vector<double> goal = p.goal, c = p.goal;
      for (std::size_t i = 0; i < space.arm.size(); ++i) {
        double& v = c[space.arm[i]];
        v = std::clamp(v + std::uniform_real_distribution<double>(-0.4, 0.4)(rng), space.group.lower[i], space.group.upper[i]);
      }
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
  double seconds = 0.0, simplify_seconds = 0.0;
  bool went_exact = false;          // ours at a tolerance: the search went on exact (planning::SearchOutcome)
  bool simplify_restored = false;   // ours: planning::simplify_certified went back to the path found
  std::uint64_t motions_exact = 0;  // and asked this many motions after
  std::vector<std::vector<double>> path;  // full states
};

// `ours`: the search by planning::solve_tolerance_first (exact after 1,000 motions at a tolerance,
// or BENCH_PLANNING_MOTIONS_AT_TOLERANCE).
Run plan(og::SimpleSetup& setup, planning::CheckerPlanningContext& layout, const Problem& p, double limit, CallTimes& calls,
         bool ours) {
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
  const ob::PlannerTerminationCondition ptc = ob::timedPlannerTerminationCondition(limit);
  planning::SearchOutcome outcome;
  if (ours) {
    static const char* at_tolerance = std::getenv("BENCH_PLANNING_MOTIONS_AT_TOLERANCE");
    const std::uint64_t motions = at_tolerance != nullptr ? std::strtoull(at_tolerance, nullptr, 10) : planning::kMotionsAtTolerance;
    outcome = planning::solve_tolerance_first(setup, layout, ptc, motions);
    run.solved = outcome.status == ob::PlannerStatus::EXACT_SOLUTION;
    run.went_exact = outcome.went_exact;
    run.motions_exact = outcome.motions_exact;
  } else {
    run.solved = setup.solve(ptc) == ob::PlannerStatus::EXACT_SOLUTION;
  }
  if (run.solved) {
    const auto s0 = std::chrono::steady_clock::now();
    calls.simplifying = true;
    if (ours) {
      // On the answers the search ended on; a result OMPL's simplifier rejects is not kept.
      run.simplify_restored = planning::simplify_certified(setup, layout, outcome).restored;
    } else {
      setup.simplifySolution();  // as MoveIt runs it
    }
    calls.simplifying = false;
    run.simplify_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - s0).count();
  }
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!run.solved) return run;
  const og::PathGeometric& path = setup.getSolutionPath();
  for (std::size_t w = 0; w < path.getStateCount(); ++w) run.path.push_back(layout.full_state(path.getState(w)));
  return run;
}

// Does any segment collide: by conservative advancement with exact distances (test/advancement_oracle.h,
// written apart from the engine that planned), and by FCL every 1e-3 rad?
std::pair<bool, bool> path_collides(const Run& run, const CollisionChecker& checker, const Environment& env, FclRobot& fcl) {
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
  int went_exact = 0, solved_exact = 0;  // searches that went on exact after the tolerance's motions, and solved so
  int restored = 0;  // simplified paths OMPL's simplifier rejected, gone back to the path found (planning::simplify_certified)
  std::vector<double> seconds;  // every problem (an unsolved one at the limit)
  CallTimes calls;
  std::vector<ProblemTimes> problems;
};

// BENCH_PLANNING_VERBOSE: one problem's plan by one checker, its calls and their times (the
// simplifier's motions apart, colliding and free).
void print_calls(const Tally& tally, const Run& run, const CallMark& before) {
  if (!std::getenv("BENCH_PLANNING_VERBOSE")) return;
  const CallTimes& c = tally.calls;
  double in_states = 0, in_motions = 0;
  for (std::size_t i = before.states; i < c.states.size(); ++i) in_states += c.states[i];
  for (std::size_t i = before.motions; i < c.motions.size(); ++i) in_motions += c.motions[i];
  const std::vector<double> motions(c.motions.begin() + static_cast<std::ptrdiff_t>(before.motions), c.motions.end());
  if (run.went_exact) std::printf("  %s: went on exact, %lu motions after\n", tally.name.c_str(), static_cast<unsigned long>(run.motions_exact));
  if (run.simplify_restored) std::printf("  %s: the simplifier's result rejected, the path found simplified exact\n", tally.name.c_str());
  std::printf("  %s: %s in %.1f ms; %zu states (%.1f ms), %zu motions (%.1f ms; us median %.0f, p90 %.0f, max %.0f); simplifier "
              "%.1f ms, its motions %ld colliding (%.1f ms) and %ld free (%.1f ms); path of %zu states\n",
              tally.name.c_str(), run.solved ? "solved" : "failed", 1e3 * run.seconds, c.states.size() - before.states, in_states / 1e3,
              motions.size(), in_motions / 1e3, bench::median(motions), bench::percentile(motions, 0.9),
              motions.empty() ? 0.0 : *std::max_element(motions.begin(), motions.end()), 1e3 * run.simplify_seconds,
              c.simplifier_motions[0] - before.simplifier_motions[0], 1e-3 * (c.simplifier_motions_us[0] - before.simplifier_motions_us[0]),
              c.simplifier_motions[1] - before.simplifier_motions[1], 1e-3 * (c.simplifier_motions_us[1] - before.simplifier_motions_us[1]),
              run.path.size());
}

// A run's figures into its checker's tally: its time (an unsolved one at the limit), where it
// went, and, solved, whether its path collides by either re-check.
void record(Tally& tally, const Run& run, const CallMark& before, double limit, const CollisionChecker& checker, const Environment& env,
            FclRobot& fcl) {
  print_calls(tally, run, before);
  tally.went_exact += run.went_exact;
  tally.solved_exact += run.went_exact && run.solved;
  tally.restored += run.simplify_restored;
  double in_calls = tally.calls.outside_motions_us - before.outside_motions_us;
  for (std::size_t i = before.motions; i < tally.calls.motions.size(); ++i) in_calls += tally.calls.motions[i];
  tally.problems.push_back({run.solved ? run.seconds : limit, run.simplify_seconds, 1e-6 * in_calls});
  tally.seconds.push_back(run.solved ? run.seconds : limit);
  if (!run.solved) return;
  ++tally.solved;
  const auto [ours, theirs] = path_collides(run, checker, env, fcl);
  tally.ours_colliding += ours;
  tally.fcl_colliding += theirs;
  if (ours || theirs) std::printf("  path collides: certified re-check %d, FCL every 1e-3 rad %d\n", int(ours), int(theirs));
}

// One problem planned by one of our configurations (tolerance 0 or 10 mm).
void plan_ours(Tally& tally, const CollisionChecker& checker, const std::shared_ptr<const Environment>& env,
               const planning::JointGroup& group, const Problem& p, double tolerance, double limit, FclRobot& fcl) {
  auto context = std::make_shared<planning::CheckerPlanningContext>(checker, env, group, p.start);
  context->tolerance = tolerance;
  context->scene();  // the object grid: built before the clock starts, as FCL's tree is
  og::SimpleSetup setup(group.make_space());
  const auto si = setup.getSpaceInformation();
  auto states = std::make_shared<planning::CheckerStateValidityChecker>(si, context);
  const bool logged = call_log.file != nullptr;
  setup.setStateValidityChecker(std::make_shared<TimedValidity>(si, [states, context, logged](const ob::State* s) {
    if (logged) call_log.state(context->full_state(s));
    return states->isValid(s);
  }, &tally.calls));
  TimedMotions::Hook hook;
  if (logged) hook = [context](const ob::State* a, const ob::State* b, bool earliest) {
    call_log.motion(context->full_state(a), context->full_state(b), earliest);
  };
  si->setMotionValidator(std::make_shared<TimedMotions>(si, std::make_shared<planning::CheckerMotionValidator>(si, context), &tally.calls, hook));
  setup.setPlanner(std::make_shared<og::RRTConnect>(si));
  setup.setup();
  const CallMark before = bench::mark(tally.calls);
  const Run run = plan(setup, *context, p, limit, tally.calls, true);
  record(tally, run, before, limit, checker, *env, fcl);
}

void plan_fcl(Tally& tally, const CollisionChecker& checker, const std::shared_ptr<const Environment>& env,
              const planning::JointGroup& group, const Problem& p, double limit, FclRobot& fcl) {
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
  const CallMark before = bench::mark(tally.calls);
  const Run run = plan(setup, *layout, p, limit, tally.calls, false);
  record(tally, run, before, limit, checker, *env, fcl);
}

struct RobotRun {
  std::string robot;
  std::size_t joints = 0, problems = 0, near = 0;
  double build_seconds = 0.0;
  std::vector<Tally> tallies;
};

void report(const std::string& out_dir, const std::vector<RobotRun>& runs, double limit) {
  Table table("planning", "Planning with RRTConnect among generated MoveIt-style scenes, per robot",
              {"robot", "checker", "problems", "solved", "median plan ms", "p95 plan ms", "median plan / FCL's",
               "per state check us (median)", "per motion check us (median)", "paths colliding (our exact certified re-check)",
               "paths colliding (FCL every 1e-3 rad)", "time in checks %", "time in simplifier %",
               "middle half: time in checks %", "middle half: time in simplifier %"});
  std::string robots;
  for (const RobotRun& r : runs) {
    const double fcl_median = bench::median(r.tallies[2].seconds);
    for (const Tally& t : r.tallies) {
      if (t.seconds.empty()) continue;  // a row left out (BENCH_PLANNING_CHECKERS)
      const bench::TimeShares shares = bench::time_shares(t.problems, false), middle = bench::time_shares(t.problems, true);
      table.row({r.robot, t.name, static_cast<double>(r.problems), static_cast<double>(t.solved), 1e3 * bench::median(t.seconds),
                 1e3 * bench::percentile(t.seconds, 0.95), fcl_median > 0 ? bench::median(t.seconds) / fcl_median : 0.0,
                 bench::median(t.calls.states), bench::median(t.calls.motions), static_cast<double>(t.ours_colliding),
                 static_cast<double>(t.fcl_colliding), 100.0 * shares.checks, 100.0 * shares.simplifier,
                 100.0 * middle.checks, 100.0 * middle.simplifier});
    }
    robots += (robots.empty() ? "" : "; ") + r.robot + ": " + std::to_string(r.joints) + " joints, " + std::to_string(r.problems) +
              " problems (" + std::to_string(r.near) + " goals within 5 mm of an obstacle), proxy levels built or read in " +
              bench::format(r.build_seconds) + " s, 10 mm searches gone on exact " + std::to_string(r.tallies[1].went_exact) +
              " (solved " + std::to_string(r.tallies[1].solved_exact) + "), simplified paths rejected and gone back to the path found " +
              std::to_string(r.tallies[0].restored + r.tallies[1].restored);
  }
  table.note(robots + ". One scene a problem: panda's and ur5e's 20-60 boxes, cylinders and spheres (tables, shelves, open "
             "boxes, cages, clutter; every other panda scene a shelf of thin boards, a dense cage of thin bars or a drawer, "
             "the goal drawn inside it), pr2's a table with a cabinet between the arms, shelves on each side and clutter (the "
             "goal drawn into one). The SRDF's allowed pairs; " + bench::format(limit) + " s a problem, then OMPL's path "
             "simplifier on the same validators (ours at 10 mm: exact after 1,000 search motions unsolved, "
             "planning::solve_tolerance_first, and the simplifier on the answers the search ended on, a result it rejects "
             "not kept: planning::simplify_certified); plan times count unsolved problems at the limit. Per-check figures are "
             "medians over every call the planners made (each call timed on its own); time in checks: the sum of those "
             "calls (for ours the adapter's state layout included) over the plan time, the rest is OMPL's own work, over every "
             "problem and over the middle half of the problems by plan time (the median plan's neighbours: over every problem "
             "the slowest weigh most). Ours: "
             "planning/ompl_validity.h (SceneChecker, certified motions), the node's proxy levels (5, 10 and 20 mm: pr2's 5 mm "
             "level, 415k spheres, fits the node's sphere budget). FCL: BVHModel<OBBRSS> link meshes and primitive URDF shapes, each checked pair "
             "behind an AABB test, primitive objects in a dynamic AABB tree, OMPL's DiscreteMotionValidator at 1 %. Scenes "
             "and problems: build/bench/scenes (MoveIt .scene text, problems.json).");
  table.write(out_dir);
}

// "pr2 torso + right arm" -> "pr2_torso_right_arm": for file names and BENCH_PLANNING_ROBOTS.
std::string file_name(const std::string& robot) {
  std::string out;
  for (const char c : robot) {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      out += c;
    } else if (!out.empty() && out.back() != '_') {
      out += '_';
    }
  }
  return out;
}

// One robot's problems, planned by the three checkers; the scenes and problems written to `dir`.
RobotRun run_robot(const PlanningRobot& robot, const std::string& out_dir, int count, double limit, std::uint64_t seed,
                   nlohmann::json& written) {
  RobotRun out;
  out.robot = robot.name;
  const CollisionChecker checker = load_robot(robot, out_dir + "/../proxy_cache", out.build_seconds);
  const planning::JointGroup group = planning::JointGroup::of(checker.model(), robot.group);
  out.joints = robot.group.size();
  const auto& all = checker.model().variable_names();
  std::vector<double> base(checker.model().variable_count(), 0.0);
  for (const auto& [name, value] : robot.base) {
    const auto at = std::find(all.begin(), all.end(), name);
    if (at == all.end()) throw std::runtime_error(robot.name + ": no variable " + name);
    base[static_cast<std::size_t>(at - all.begin())] = value;
  }
  ProblemSpace space{group, {}, base, std::nullopt, checker.model().link_index(robot.tip)};
  if (space.tip < 0) throw std::runtime_error(robot.name + ": no link " + robot.tip);
  for (const std::string& name : robot.group) space.arm.push_back(static_cast<int>(std::find(all.begin(), all.end(), name) - all.begin()));
  const FclLinkModels fcl_models = fcl_link_models(checker.model());
  std::mt19937_64 rng(seed);
  out.tallies.resize(3);
  out.tallies[0].name = "ours, exact (tolerance 0)";
  out.tallies[1].name = "ours, 10 mm";
  out.tallies[2].name = "FCL + discrete motions at 1 %";
  const char* only = std::getenv("BENCH_PLANNING_CHECKERS");
  const auto runs = [&](char row) { return only == nullptr || std::string(only).find(row) != std::string::npos; };
  std::filesystem::create_directories(out_dir + "/scenes");
  if (const char* replay = std::getenv("BENCH_PLANNING_REPLAY")) logged_calls = bench::read_call_log(replay, checker.model().variable_count());
  bench::ReplayCount replayed[2];
  for (int k = 0; k < count; ++k) {
    const test::PlanningScene scene = robot.scene(seed, k, space.target);
    const auto env = std::make_shared<const Environment>(scene.environment());
    const SceneChecker exact(checker, env);
    const Problem p = make_problem(exact, k, rng, space);
    out.near += p.near;
    ++out.problems;
    const std::string scene_file = file_name(robot.name) + "_scene_" + std::to_string(k) + ".scene";
    std::ofstream text(out_dir + "/scenes/" + scene_file);
    write_scene_text(scene, text);
    written.push_back({{"robot", robot.name}, {"group", robot.group}, {"scene", scene_file}, {"start", p.start}, {"goal", p.goal},
                       {"goal_within_5mm", p.near}, {"goal_clearance", p.goal_clearance}});
    FclRobot fcl(checker, fcl_models, scene);
    auto& t = out.tallies;
    if (!logged_calls.empty()) {
      for (const int row : {0, 1}) {
        if (runs(static_cast<char>('0' + row))) bench::replay_problem(checker, env, logged_calls, k, row, replayed[row]);
      }
      continue;
    }
    call_log.problem = k;
    call_log.row = 0;
    if (runs('0')) plan_ours(t[0], checker, env, group, p, 0.0, limit, fcl);
    call_log.row = 1;
    if (runs('1')) plan_ours(t[1], checker, env, group, p, 0.01, limit, fcl);
    if (runs('2')) plan_fcl(t[2], checker, env, group, p, limit, fcl);
    std::printf("%s problem %d (%zu shapes%s): solved %d/%d/%d so far\n", robot.name.c_str(), k, scene.shape_count(),
                p.near ? ", goal near" : "", t[0].solved, t[1].solved, t[2].solved);
    std::fflush(stdout);
  }
  for (int row = 0; row < 2; ++row) bench::print_replay(robot.name, out.tallies[static_cast<std::size_t>(row)].name, checker, replayed[row]);
  return out;
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  using namespace bvh_collision;
  const std::string out_dir = bench::output_dir(argc, argv);
  const bool quick = bench::quick_mode(argc, argv);
  const char* problems = std::getenv("BENCH_PLANNING_PROBLEMS");
  const int count = problems != nullptr ? std::atoi(problems) : quick ? 1 : 100;
  const double limit = quick ? 2.0 : 10.0;
  const std::uint64_t seed = 2026;
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  const char* ompl_seed = std::getenv("BENCH_PLANNING_OMPL_SEED");  // another draw of the planner's randomness
  ompl::RNG::setSeed(ompl_seed != nullptr ? std::strtoul(ompl_seed, nullptr, 10) : 1);
  const char* only = std::getenv("BENCH_PLANNING_ROBOTS");
  if (const char* log = std::getenv("BENCH_PLANNING_LOG")) {
    call_log.file = std::fopen(log, "w");
    if (call_log.file == nullptr) throw std::runtime_error(std::string("cannot write ") + log);
  }
  std::vector<RobotRun> runs;
  nlohmann::json written = nlohmann::json::array();
  for (const PlanningRobot& robot : planning_robots()) {
    if (only != nullptr && ("," + std::string(only) + ",").find("," + file_name(robot.name) + ",") == std::string::npos) continue;
    runs.push_back(run_robot(robot, out_dir, count, limit, seed, written));
  }
  std::ofstream(out_dir + "/scenes/problems.json") << written.dump(1) << "\n";
  if (call_log.file != nullptr) std::fclose(call_log.file);
  if (!logged_calls.empty()) return 0;  // a replay plans nothing to report
  report(out_dir, runs, limit);
  return 0;
}
