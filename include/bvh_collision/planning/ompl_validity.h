// OMPL over the checker, in-process: a StateValidityChecker and a MotionValidator that answer a
// sampling planner's questions with CollisionChecker's queries on one environment snapshot. The
// motion validator is the certified check_motion (no collision hides between the states it
// checks), so a path made of motions it accepted is free along its whole length, not only at its
// waypoints: OMPL's default validator checks states a fixed fraction of the space apart and can
// step over a thin obstacle. Plain C++ and OMPL: no ROS (the ros layer's service-backed twins are
// in ros/planning/service_validity.h).
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>

#include "bvh_collision/checker/collision_checker.h"
#include "bvh_collision/checker/scene_checker.h"

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

// How many questions the planner asked and the time spent answering them (both validators of
// one planning run share one): the figures plan_demo prints.
struct ValidityCounters {
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
// the part of its kind.
class ValidityTimer {
 public:
  explicit ValidityTimer(ValidityCounters* counters, CheckKind kind = CheckKind::kOther)
      : counters_(counters), kind_(kind), start_(std::chrono::steady_clock::now()) {}
  ~ValidityTimer();
  ValidityTimer(const ValidityTimer&) = delete;
  ValidityTimer& operator=(const ValidityTimer&) = delete;

 private:
  ValidityCounters* counters_;
  CheckKind kind_;
  std::chrono::steady_clock::time_point start_;
};

// What the validators check and against what: the robot's other variables stay at `base_state`.
struct CheckerPlanningContext {
  CollisionChecker checker;
  std::shared_ptr<const Environment> environment;  // a snapshot: never changes under the planner
  JointGroup group;
  std::vector<double> base_state;  // every variable of the model (variable_names() order)
  bool self = true, obstacles = true;
  // DESIGN.md section 2. A free answer is free at any tolerance (every distance exceeds its
  // padding); the tolerance only lets a state or motion within it of a collision count as
  // colliding, which lets the proxy levels answer: 1 cm by default (with levels of 5 mm or
  // coarser built: CheckerOptions::proxy_levels); 0 asks for exact answers.
  double tolerance = 0.01;
  Transform root_pose;              // the root link in the environment's frame
  std::shared_ptr<ValidityCounters> counters = std::make_shared<ValidityCounters>();

  // Throws std::invalid_argument when the base state's size or the group does not fit the model.
  CheckerPlanningContext(CollisionChecker checker, std::shared_ptr<const Environment> environment, JointGroup group,
                         std::vector<double> base_state);
  // The full robot state for a planner state (the group's values written into the base state).
  std::vector<double> full_state(const ompl::base::State* state) const;
  // The same into `full` (resized): no allocation once it has the size.
  void full_state(const ompl::base::State* state, std::vector<double>& full) const;
  // The checker the validators ask (checker/scene_checker.h), built on first use from the
  // fields above as they are then (set them before planning); shared by both validators.
  const SceneChecker& scene() const;

 private:
  std::vector<int> variables_;  // the group's entries in the full state
  mutable std::once_flag scene_once_;
  mutable std::unique_ptr<const SceneChecker> scene_;
};

class CheckerStateValidityChecker : public ompl::base::StateValidityChecker {
 public:
  CheckerStateValidityChecker(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<const CheckerPlanningContext> context);
  // Free of self-collision and of the environment (at the context's tolerance).
  bool isValid(const ompl::base::State* state) const override;
  // The exact distance to the nearest collision (self pairs and obstacles); 0 in collision.
  double clearance(const ompl::base::State* state) const override;

 private:
  std::shared_ptr<const CheckerPlanningContext> context_;
};

class CheckerMotionValidator : public ompl::base::MotionValidator {
 public:
  CheckerMotionValidator(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<const CheckerPlanningContext> context);
  // The straight motion in joint space, certified (SceneChecker::check_motion).
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2) const override;
  // The same; when it collides, `last_valid` gets the last state found free and its fraction.
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2,
                   std::pair<ompl::base::State*, double>& last_valid) const override;

 private:
  // `earliest`: the first collision (for last_valid), else any.
  MotionResult check(const ompl::base::State* s1, const ompl::base::State* s2, bool earliest) const;
  std::shared_ptr<const CheckerPlanningContext> context_;
};

}  // namespace bvh_collision::planning
