// OMPL over the checker: one StateValidityChecker and one MotionValidator (StateValidity,
// MotionValidity) over a context that answers a sampling planner's questions. The context here,
// CheckerPlanningContext, answers in-process with SceneChecker on one environment snapshot; the
// ros layer's ServicePlanningContext (ros/service_validity.h) asks a running node's services. The
// motion validator is the certified check_motion (no collision hides between the states it
// checks), so a path made of motions it accepted is free along its whole length, not only at its
// waypoints: OMPL's default validator checks states a fixed fraction of the space apart and can
// step over a thin obstacle. Plain C++ and OMPL: no ROS.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/PlannerStatus.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"

namespace bvh_collision::planning {

// The joints a planner moves and their bounds: the planner's space is the box of the bounds.
struct JointGroup {
  std::vector<std::string> names;
  std::vector<double> lower, upper;

  // The named state variables of `model` (all of them when `names` is empty), within their
  // limits (a continuous joint: [-pi, pi]). Throws std::invalid_argument for a name that is not
  // a variable of the model.
  static JointGroup of(const RobotModel& model, const std::vector<std::string>& names = {});
  std::size_t size() const { return names.size(); }
  // OMPL's real vector space over the group, bounded as above, its dimensions named.
  std::shared_ptr<ompl::base::RealVectorStateSpace> make_space() const;
};

// How many questions the planner asked and, when `timed`, the time spent answering them (both
// validators of one planning run share one): the figures plan_demo prints. Timing is off by
// default: two clock reads and three atomic sums cost about a tenth of a state check.
struct ValidityCounters {
  bool timed = false;  // set before planning starts
  std::atomic<std::uint64_t> states{0}, motions{0}, nanoseconds{0};
  std::atomic<std::uint64_t> state_nanoseconds{0}, motion_nanoseconds{0};  // the part in each kind
  double seconds() const { return 1e-9 * static_cast<double>(nanoseconds.load()); }
  // The mean cost of one state check and of one motion check (microseconds; 0 before any).
  double us_per_state() const { return states ? 1e-3 * static_cast<double>(state_nanoseconds.load()) / static_cast<double>(states.load()) : 0.0; }
  double us_per_motion() const { return motions ? 1e-3 * static_cast<double>(motion_nanoseconds.load()) / static_cast<double>(motions.load()) : 0.0; }
  void reset() { states = 0, motions = 0, nanoseconds = 0, state_nanoseconds = 0, motion_nanoseconds = 0; }
};

enum class CheckKind { kState, kMotion, kOther };

// Adds the time from construction to destruction to `counters` (exceptions included), and to
// the part of its kind, when the counters are timed.
class ValidityTimer {
 public:
  explicit ValidityTimer(ValidityCounters* counters, CheckKind kind = CheckKind::kOther)
      : counters_(counters), kind_(kind) {
    if (counters_->timed) start_ = std::chrono::steady_clock::now();
  }
  ~ValidityTimer();
  ValidityTimer(const ValidityTimer&) = delete;
  ValidityTimer& operator=(const ValidityTimer&) = delete;

 private:
  ValidityCounters* counters_;
  CheckKind kind_;
  std::chrono::steady_clock::time_point start_;
};

// A planner's motion as a context answers it: free, or the fraction of the way to the last state
// found free (to the first collision when the earliest was asked for).
struct MotionAnswer {
  bool valid = false;
  double last_valid_fraction = 0.0;
};

// A pair of planner states: a motion from the first to the second.
using StatePair = std::pair<const ompl::base::State*, const ompl::base::State*>;

// The values of a planner state of JointGroup::make_space()'s space.
inline const double* state_values(const ompl::base::State* state) {
  return state->as<ompl::base::RealVectorStateSpace::StateType>()->values;
}

// What the validators check and against what, in-process: the robot's other variables stay at
// `base_state`.
struct CheckerPlanningContext {
  CollisionChecker checker;
  std::shared_ptr<const Environment> environment;  // a snapshot: never changes under the planner
  JointGroup group;
  std::vector<double> base_state;  // every variable of the model (variable_names() order)
  bool self = true, obstacles = true;
  // docs/design.md. A free answer is free at any tolerance (every distance exceeds its
  // padding); the tolerance only lets a state or motion within it of a collision count as
  // colliding, which lets the proxy levels answer: 1 cm by default (with levels of 5 mm or
  // coarser built: CheckerOptions::proxy_levels); 0 asks for exact answers.
  double tolerance = 0.01;
  Transform root_pose;              // the root link in the environment's frame
  std::shared_ptr<ValidityCounters> counters = std::make_shared<ValidityCounters>();
  // While set, every answer is exact (tolerance 0) whatever `tolerance` says: what
  // solve_tolerance_first sets for the rest of a search the tolerance has not solved.
  std::atomic<bool> exact{false};

  // Throws std::invalid_argument when the base state's size or the group does not fit the model.
  CheckerPlanningContext(CollisionChecker checker, std::shared_ptr<const Environment> environment, JointGroup group,
                         std::vector<double> base_state);
  // The full robot state for a planner state (the group's values written into the base state).
  std::vector<double> full_state(const ompl::base::State* state) const;
  // The same into `full` (resized): no allocation once it has the size.
  void full_state(const ompl::base::State* state, std::vector<double>& full) const;
  // The checker the validators ask (query/scene_checker.h), built on first use from the
  // fields above as they are then (set them before planning); shared by both validators.
  const SceneChecker& scene() const;
  // The checker at tolerance 0 (the same as scene() when `tolerance` is 0), built on first use.
  const SceneChecker& exact_scene() const;

  // The validators' questions (see StateValidity): free of self-collision and of the
  // environment at the tolerance; the certified motion (SceneChecker::check_motion); several
  // motions, each alone; the exact distance to the nearest collision (0 in collision).
  bool check_state(const ompl::base::State* state) const;
  MotionAnswer check_motion(const ompl::base::State* from, const ompl::base::State* to, bool earliest) const;
  std::vector<bool> check_motions(const std::vector<StatePair>& motions) const;
  double clearance(const ompl::base::State* state) const;

 private:
  std::vector<int> variables_;  // the group's entries in the full state
  mutable std::once_flag scene_once_;
  mutable std::unique_ptr<const SceneChecker> scene_;
  mutable std::once_flag exact_once_;
  mutable std::unique_ptr<const SceneChecker> exact_scene_;
  const SceneChecker& answering() const { return exact ? exact_scene() : scene(); }
};

// A search at a tolerance, then exact (docs/planning.md, "A passage the tolerance closes").
// A tolerance only turns free answers within it of a collision into colliding ones, so it can
// close a passage a few millimetres wider than the robot, where a search then asks until its
// limit. solve_tolerance_first runs `setup`'s planner (its validators over `context`) until
// `ptc` at the context's tolerance for the first `motions_at_tolerance` motion checks, and then,
// unsolved, goes on with exact answers: the planner keeps its trees, since every motion the
// tolerance let through is free exactly too. The context answers at its tolerance again on
// return (simplify_certified below simplifies on the answers the search ended on). Motions are counted by the
// context's counters (a validator of this header); with no tolerance, one plain solve.
struct SearchOutcome {
  ompl::base::PlannerStatus status;
  bool went_exact = false;  // the count ran out unsolved and the search went on exact
  std::uint64_t motions_at_tolerance = 0, motions_exact = 0;  // all exact at tolerance 0
};
// About the 95th percentile of the search motions of the plans the 10 mm rows of bench_planning
// solve on panda (docs/planning.md): the typical search never gets there.
constexpr std::uint64_t kMotionsAtTolerance = 1000;
SearchOutcome solve_tolerance_first(ompl::geometric::SimpleSetup& setup, CheckerPlanningContext& context,
                                    const ompl::base::PlannerTerminationCondition& ptc,
                                    std::uint64_t motions_at_tolerance = kMotionsAtTolerance);

// OMPL's path simplifier on `setup`'s solution path, its result kept only when the simplifier
// accepts it; else the path found is put back (returns false). The simplifier takes only a
// shortcut its validators find free, but it ends by re-checking every segment and "repairs" one
// they reject by sampling states near it: when no repair serves, it leaves the last sampled state
// in the path, with motions no check found free, and says so by its answer, which
// SimpleSetup::simplifySolution drops. Certified validators at a tolerance can reject a segment
// they or exact answers accepted before (a tolerance lets, not makes, a motion within it of a
// collision count as colliding), so over them a simplifier's result needs this check.
bool simplify_or_keep(ompl::geometric::SimpleSetup& setup,
                      const ompl::base::PlannerTerminationCondition& ptc = ompl::base::plannerNonTerminatingCondition());

// simplify_or_keep for a path solve_tolerance_first found (docs/planning.md, "Simplifying a
// path"). A search that went on exact can return a segment within the tolerance of an obstacle,
// which the tolerance's answers may reject: its path is simplified on exact answers. A result the
// simplifier rejects at the tolerance goes back to the path found, simplified exact (a segment
// found free is free exactly, and so is every part of it); rejected exact too, the path found
// stands. The context answers at its tolerance again on return.
struct SimplifyOutcome {
  bool simplified = false;  // the simplifier's result was kept (else the path found, unchanged)
  bool exact = false;       // on exact answers
  bool restored = false;    // a result was rejected and the path found went back (simplified exact once more)
};
SimplifyOutcome simplify_certified(ompl::geometric::SimpleSetup& setup, CheckerPlanningContext& context, const SearchOutcome& search,
                                   const ompl::base::PlannerTerminationCondition& ptc = ompl::base::plannerNonTerminatingCondition());

namespace detail {
template <class Context, class = void>
struct MeasuresClearance : std::false_type {};
template <class Context>
struct MeasuresClearance<Context, std::void_t<decltype(std::declval<const Context&>().clearance(nullptr))>> : std::true_type {};
}  // namespace detail

// The state validity checker over a context that offers
//   std::shared_ptr<ValidityCounters> counters;
//   bool check_state(const ompl::base::State*) const;
// and, when it can measure one, double clearance(const ompl::base::State*) const (exact).
// Counts and times every question in the context's counters.
template <class Context>
class StateValidity : public ompl::base::StateValidityChecker {
 public:
  StateValidity(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<const Context> context)
      : ompl::base::StateValidityChecker(si), context_(std::move(context)) {
    if constexpr (detail::MeasuresClearance<Context>::value) {
      specs_.clearanceComputationType = ompl::base::StateValidityCheckerSpecs::EXACT;
    }
  }
  bool isValid(const ompl::base::State* state) const override {
    ++context_->counters->states;
    ValidityTimer timer(context_->counters.get(), CheckKind::kState);
    return context_->check_state(state);
  }
  double clearance(const ompl::base::State* state) const override {
    if constexpr (detail::MeasuresClearance<Context>::value) {
      ValidityTimer timer(context_->counters.get());
      return context_->clearance(state);
    } else {
      return ompl::base::StateValidityChecker::clearance(state);
    }
  }

 private:
  std::shared_ptr<const Context> context_;
};

// The motion validator over a context that offers
//   MotionAnswer check_motion(const ompl::base::State*, const ompl::base::State*, bool earliest) const;
//   std::vector<bool> check_motions(const std::vector<StatePair>&) const;  // one answer a motion
// (and the counters). The straight motion in joint space, certified.
template <class Context>
class MotionValidity : public ompl::base::MotionValidator {
 public:
  MotionValidity(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<const Context> context)
      : ompl::base::MotionValidator(si), context_(std::move(context)) {}
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2) const override {
    return count(check(s1, s2, false).valid);
  }
  // The same; when it collides, `last_valid` gets the last state found free and its fraction.
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2,
                   std::pair<ompl::base::State*, double>& last_valid) const override {
    const MotionAnswer a = check(s1, s2, true);
    if (!a.valid) {
      last_valid.second = a.last_valid_fraction;
      if (last_valid.first != nullptr) si_->getStateSpace()->interpolate(s1, s2, a.last_valid_fraction, last_valid.first);
    }
    return count(a.valid);
  }
  // Several motions in one call, for a caller that has them at once (a lazy planner's candidate
  // path, a path's segments to certify): each answered as checkMotion answers it alone (over a
  // node's services: one check_motions call).
  std::vector<bool> checkMotions(const std::vector<StatePair>& motions) const {
    if (motions.empty()) return {};
    context_->counters->motions += motions.size();
    ValidityTimer timer(context_->counters.get(), CheckKind::kMotion);
    const std::vector<bool> free = context_->check_motions(motions);
    for (const bool f : free) count(f);
    return free;
  }

 private:
  MotionAnswer check(const ompl::base::State* s1, const ompl::base::State* s2, bool earliest) const {
    ++context_->counters->motions;
    ValidityTimer timer(context_->counters.get(), CheckKind::kMotion);
    return context_->check_motion(s1, s2, earliest);
  }
  bool count(bool free) const {
    ++(free ? valid_ : invalid_);
    return free;
  }
  std::shared_ptr<const Context> context_;
};

using CheckerStateValidityChecker = StateValidity<CheckerPlanningContext>;
using CheckerMotionValidator = MotionValidity<CheckerPlanningContext>;

}  // namespace bvh_collision::planning
