#include "bvh_collision/ros/service_validity.h"

#include <stdexcept>

#include <ompl/base/SpaceInformation.h>

#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/CheckMotions.h"
#include "bvh_collision/CheckState.h"
#include "bvh_collision/CheckStates.h"
#include "bvh_collision/ros/readiness.h"

namespace bvh_collision {
namespace {

const double* values(const ompl::base::State* state) {
  return state->as<ompl::base::RealVectorStateSpace::StateType>()->values;
}

template <class Service>
void call(ros::ServiceClient& client, Service& srv) {
  if (!client.isValid() || !client.call(srv)) {
    throw std::runtime_error("calling " + client.getService() + " failed (is the collision checker running?)");
  }
  if (!srv.response.error.empty()) throw std::runtime_error(client.getService() + ": " + srv.response.error);
}

}  // namespace

ServicePlanningContext::ServicePlanningContext(const std::string& checker, planning::JointGroup group_, double timeout)
    : group(std::move(group_)) {
  if (!wait_until_ready(checker, timeout)) {
    throw std::runtime_error(checker + " did not become ready (~ready) within " + std::to_string(timeout) + " s");
  }
  ros::NodeHandle nh(checker);
  state_ = nh.serviceClient<CheckState>("check_state", true);
  states_ = nh.serviceClient<CheckStates>("check_states", true);
  motion_ = nh.serviceClient<CheckMotion>("check_motion", true);
  motions_ = nh.serviceClient<CheckMotions>("check_motions", true);
  for (ros::ServiceClient* c : {&state_, &states_, &motion_, &motions_}) {
    if (!c->waitForExistence(ros::Duration(timeout))) {
      throw std::runtime_error("no service " + c->getService() + " within " + std::to_string(timeout) + " s");
    }
  }
}

bool ServicePlanningContext::state_valid(const double* v) const {
  CheckState srv;
  srv.request.state.name = group.names;
  srv.request.state.position.assign(v, v + group.size());
  srv.request.checks = checks;
  srv.request.tolerance = tolerance;
  std::lock_guard<std::mutex> lock(mutex_);
  call(state_, srv);
  return srv.response.valid;
}

bool ServicePlanningContext::motion_valid(const double* start, const double* goal, double* last_valid_fraction) const {
  CheckMotion srv;
  srv.request.joint_names = group.names;
  srv.request.start.assign(start, start + group.size());
  srv.request.goal.assign(goal, goal + group.size());
  srv.request.checks = checks;
  srv.request.resolution = 0.0;  // certified
  std::lock_guard<std::mutex> lock(mutex_);
  call(motion_, srv);
  if (last_valid_fraction) *last_valid_fraction = srv.response.last_valid_fraction;
  return srv.response.valid;
}

std::vector<bool> ServicePlanningContext::motions_valid(const double* starts, const double* goals, std::size_t count,
                                                       std::vector<double>* last_valid_fractions) const {
  CheckMotions srv;
  srv.request.joint_names = group.names;
  srv.request.starts.assign(starts, starts + count * group.size());
  srv.request.goals.assign(goals, goals + count * group.size());
  srv.request.checks = checks;
  std::lock_guard<std::mutex> lock(mutex_);
  call(motions_, srv);
  if (srv.response.valid.size() != count || srv.response.last_valid_fraction.size() != count) {
    throw std::runtime_error("check_motions answered for a different count");
  }
  if (last_valid_fractions) *last_valid_fractions = srv.response.last_valid_fraction;
  return std::vector<bool>(srv.response.valid.begin(), srv.response.valid.end());
}

std::vector<bool> ServicePlanningContext::states_valid(const double* v, std::size_t count) const {
  CheckStates srv;
  srv.request.joint_names = group.names;
  srv.request.positions.assign(v, v + count * group.size());
  srv.request.checks = checks;
  srv.request.tolerance = tolerance;
  std::lock_guard<std::mutex> lock(mutex_);
  call(states_, srv);
  if (srv.response.valid.size() != count) throw std::runtime_error("check_states answered for a different count");
  return std::vector<bool>(srv.response.valid.begin(), srv.response.valid.end());
}

ServiceStateValidityChecker::ServiceStateValidityChecker(const ompl::base::SpaceInformationPtr& si,
                                                         std::shared_ptr<const ServicePlanningContext> context)
    : ompl::base::StateValidityChecker(si), context_(std::move(context)) {}

bool ServiceStateValidityChecker::isValid(const ompl::base::State* state) const {
  ++context_->counters->states;
  planning::ValidityTimer timer(context_->counters.get(), planning::CheckKind::kState);
  return context_->state_valid(values(state));
}

ServiceMotionValidator::ServiceMotionValidator(const ompl::base::SpaceInformationPtr& si,
                                               std::shared_ptr<const ServicePlanningContext> context)
    : ompl::base::MotionValidator(si), context_(std::move(context)) {}

bool ServiceMotionValidator::checkMotion(const ompl::base::State* s1, const ompl::base::State* s2) const {
  ++context_->counters->motions;
  planning::ValidityTimer timer(context_->counters.get(), planning::CheckKind::kMotion);
  const bool free = context_->motion_valid(values(s1), values(s2));
  ++(free ? valid_ : invalid_);
  return free;
}

std::vector<bool> ServiceMotionValidator::checkMotions(
    const std::vector<std::pair<const ompl::base::State*, const ompl::base::State*>>& motions) const {
  if (motions.empty()) return {};
  context_->counters->motions += motions.size();
  planning::ValidityTimer timer(context_->counters.get(), planning::CheckKind::kMotion);
  const std::size_t n = context_->group.size();
  std::vector<double> starts, goals;
  for (const auto& [a, b] : motions) {
    starts.insert(starts.end(), values(a), values(a) + n);
    goals.insert(goals.end(), values(b), values(b) + n);
  }
  const std::vector<bool> free = context_->motions_valid(starts.data(), goals.data(), motions.size());
  for (const bool f : free) ++(f ? valid_ : invalid_);
  return free;
}

bool ServiceMotionValidator::checkMotion(const ompl::base::State* s1, const ompl::base::State* s2,
                                         std::pair<ompl::base::State*, double>& last_valid) const {
  ++context_->counters->motions;
  planning::ValidityTimer timer(context_->counters.get(), planning::CheckKind::kMotion);
  double fraction = 0.0;
  const bool free = context_->motion_valid(values(s1), values(s2), &fraction);
  if (!free) {
    last_valid.second = fraction;
    if (last_valid.first != nullptr) si_->getStateSpace()->interpolate(s1, s2, fraction, last_valid.first);
  }
  ++(free ? valid_ : invalid_);
  return free;
}

}  // namespace bvh_collision
