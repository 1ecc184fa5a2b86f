#include "bvh_collision/planning/ompl_validity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace bvh_collision::planning {
namespace {

constexpr double kPi = 3.141592653589793;

}  // namespace

JointGroup JointGroup::of(const RobotModel& model, const std::vector<std::string>& names) {
  JointGroup g;
  g.names = names.empty() ? model.variable_names() : names;
  for (const std::string& name : g.names) {
    const auto& all = model.variable_names();
    if (std::find(all.begin(), all.end(), name) == all.end()) {
      throw std::invalid_argument("'" + name + "' is not a joint variable of robot '" + model.name() + "'");
    }
    const RobotJoint& joint = model.joints()[model.joint_index(name)];
    const bool limited = joint.bounded && std::isfinite(joint.lower) && std::isfinite(joint.upper);
    g.lower.push_back(limited ? joint.lower : -kPi);
    g.upper.push_back(limited ? joint.upper : kPi);
  }
  return g;
}

std::shared_ptr<ompl::base::RealVectorStateSpace> JointGroup::make_space() const {
  auto space = std::make_shared<ompl::base::RealVectorStateSpace>(static_cast<unsigned>(size()));
  ompl::base::RealVectorBounds bounds(static_cast<unsigned>(size()));
  for (std::size_t i = 0; i < size(); ++i) {
    bounds.setLow(static_cast<unsigned>(i), lower[i]);
    bounds.setHigh(static_cast<unsigned>(i), upper[i]);
    space->setDimensionName(static_cast<unsigned>(i), names[i]);
  }
  space->setBounds(bounds);
  return space;
}

ValidityTimer::~ValidityTimer() {
  if (!counters_->timed) return;
  const auto spent = std::chrono::steady_clock::now() - start_;
  const auto ns = static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(spent).count());
  counters_->nanoseconds += ns;
  if (kind_ == CheckKind::kState) counters_->state_nanoseconds += ns;
  if (kind_ == CheckKind::kMotion) counters_->motion_nanoseconds += ns;
}

CheckerPlanningContext::CheckerPlanningContext(CollisionChecker checker_, std::shared_ptr<const Environment> environment_,
                                               JointGroup group_, std::vector<double> base_state_)
    : checker(std::move(checker_)),
      environment(std::move(environment_)),
      group(std::move(group_)),
      base_state(std::move(base_state_)) {
  const RobotModel& model = checker.model();
  if (base_state.size() != model.variable_count()) {
    throw std::invalid_argument("the base state has " + std::to_string(base_state.size()) + " values; robot '" +
                                model.name() + "' has " + std::to_string(model.variable_count()) + " variables");
  }
  if (!environment) throw std::invalid_argument("no environment to plan in");
  // The objects the environment has the robot carry, carried in every check (a checker given
  // carrying them already is used as it is).
  if (!checker.carries(*environment)) checker = checker.carrying(*environment);
  for (const std::string& name : group.names) {
    const auto& all = model.variable_names();
    const auto it = std::find(all.begin(), all.end(), name);
    if (it == all.end()) throw std::invalid_argument("'" + name + "' is not a joint variable of the robot");
    variables_.push_back(static_cast<int>(it - all.begin()));
  }
}

std::vector<double> CheckerPlanningContext::full_state(const ompl::base::State* state) const {
  std::vector<double> full;
  full_state(state, full);
  return full;
}

void CheckerPlanningContext::full_state(const ompl::base::State* state, std::vector<double>& full) const {
  full.assign(base_state.begin(), base_state.end());
  const double* v = state_values(state);
  for (std::size_t i = 0; i < variables_.size(); ++i) full[variables_[i]] = v[i];
}

const SceneChecker& CheckerPlanningContext::scene() const {
  std::call_once(scene_once_, [&] {
    SceneCheckOptions options;
    options.self = self;
    options.environment = obstacles;
    options.tolerance = tolerance;
    options.root_pose = root_pose;
    scene_ = std::make_unique<const SceneChecker>(checker, environment, options);
  });
  return *scene_;
}

const SceneChecker& CheckerPlanningContext::exact_scene() const {
  if (tolerance == 0.0) return scene();
  std::call_once(exact_once_, [&] {
    SceneCheckOptions options;
    options.self = self;
    options.environment = obstacles;
    options.root_pose = root_pose;
    exact_scene_ = std::make_unique<const SceneChecker>(checker, environment, options);
  });
  return *exact_scene_;
}

bool CheckerPlanningContext::check_state(const ompl::base::State* state) const {
  thread_local std::vector<double> q;
  full_state(state, q);
  return !answering().collides(q.data());
}

MotionAnswer CheckerPlanningContext::check_motion(const ompl::base::State* from, const ompl::base::State* to,
                                                  bool earliest) const {
  thread_local std::vector<double> a, b;
  full_state(from, a);
  full_state(to, b);
  const MotionResult r = answering().check_motion(a.data(), b.data(), earliest);
  return {r.valid, r.last_valid_fraction};
}

std::vector<bool> CheckerPlanningContext::check_motions(const std::vector<StatePair>& motions) const {
  std::vector<bool> free;
  free.reserve(motions.size());
  for (const auto& [from, to] : motions) free.push_back(check_motion(from, to, false).valid);
  return free;
}

double CheckerPlanningContext::clearance(const ompl::base::State* state) const {
  const std::vector<double> q = full_state(state);
  double nearest = std::numeric_limits<double>::infinity();
  if (self) {
    SelfCollisionRequest request;
    request.distance = true;
    request.all_pairs = true;
    const SelfCollisionResult r = checker.check_self(q.data(), request);
    nearest = r.collision ? 0.0 : std::min(nearest, r.min_distance);
  }
  if (obstacles && nearest > 0.0) {
    EnvironmentRequest request;
    request.distance = true;
    request.all_links = true;
    request.contacts = false;
    request.root_pose = root_pose;
    const EnvironmentResult r = checker.check_environment(q.data(), *environment, request);
    nearest = r.collision ? 0.0 : std::min(nearest, r.min_distance);
  }
  return nearest;
}

SearchOutcome solve_tolerance_first(ompl::geometric::SimpleSetup& setup, CheckerPlanningContext& context,
                                    const ompl::base::PlannerTerminationCondition& ptc, std::uint64_t motions_at_tolerance) {
  namespace ob = ompl::base;
  const std::uint64_t start = context.counters->motions;
  const auto asked = [&] { return context.counters->motions - start; };
  SearchOutcome outcome;
  context.exact = false;
  if (context.tolerance == 0.0) {
    outcome.status = setup.solve(ptc);
    outcome.motions_exact = asked();
    return outcome;
  }
  outcome.status = setup.solve(ob::plannerOrTerminationCondition(
      ptc, ob::PlannerTerminationCondition([&] { return asked() >= motions_at_tolerance; })));
  outcome.motions_at_tolerance = asked();
  // Only a search stopped by the count goes on: a solution, a bad start or goal, or the caller's
  // own limit ends it here (an approximate solution is a search stopped unsolved).
  const bool stopped = outcome.status == ob::PlannerStatus::TIMEOUT || outcome.status == ob::PlannerStatus::APPROXIMATE_SOLUTION;
  if (!stopped || ptc()) return outcome;
  context.exact = true;
  outcome.went_exact = true;
  try {
    outcome.status = setup.solve(ptc);
  } catch (...) {
    context.exact = false;
    throw;
  }
  context.exact = false;
  outcome.motions_exact = asked() - outcome.motions_at_tolerance;
  return outcome;
}

bool simplify_or_keep(ompl::geometric::SimpleSetup& setup, const ompl::base::PlannerTerminationCondition& ptc) {
  ompl::geometric::PathGeometric& path = setup.getSolutionPath();
  const ompl::geometric::PathGeometric found = path;
  if (setup.getPathSimplifier()->simplify(path, ptc)) return true;
  path = found;
  return false;
}

SimplifyOutcome simplify_certified(ompl::geometric::SimpleSetup& setup, CheckerPlanningContext& context, const SearchOutcome& search,
                                   const ompl::base::PlannerTerminationCondition& ptc) {
  // Simplifies on exact answers or the tolerance's; the context is back at its tolerance after.
  const auto simplify = [&](bool exact) {
    context.exact = exact;
    try {
      const bool kept = simplify_or_keep(setup, ptc);
      context.exact = false;
      return kept;
    } catch (...) {
      context.exact = false;
      throw;
    }
  };
  SimplifyOutcome outcome;
  outcome.exact = search.went_exact || context.tolerance == 0.0;
  outcome.simplified = simplify(outcome.exact);
  if (outcome.simplified) return outcome;
  outcome.restored = true;
  if (outcome.exact) return outcome;  // rejected on exact answers already: the path found stands
  outcome.exact = true;
  outcome.simplified = simplify(true);
  return outcome;
}

}  // namespace bvh_collision::planning
