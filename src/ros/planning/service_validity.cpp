#include "bvh_collision/ros/service_validity.h"

#include <stdexcept>

#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/CheckMotions.h"
#include "bvh_collision/CheckState.h"
#include "bvh_collision/CheckStates.h"
#include "bvh_collision/PinWorld.h"
#include "bvh_collision/ros/readiness.h"

namespace bvh_collision {
namespace {

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
  pin_ = nh.serviceClient<PinWorld>("pin_world", true);
  for (ros::ServiceClient* c : {&state_, &states_, &motion_, &motions_, &pin_}) {
    if (!c->waitForExistence(ros::Duration(timeout))) {
      throw std::runtime_error("no service " + c->getService() + " within " + std::to_string(timeout) + " s");
    }
  }
}

ServicePlanningContext::~ServicePlanningContext() {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    release();
  } catch (const std::exception&) {  // the node may be gone: its pin expires there
  }
}

void ServicePlanningContext::release() const {
  if (pinned_ == 0) return;
  PinWorld srv;
  srv.request.release = true;
  srv.request.version = pinned_;
  pinned_ = 0;
  call(pin_, srv);
}

void ServicePlanningContext::new_plan() {
  std::lock_guard<std::mutex> lock(mutex_);
  release();
}

std::uint64_t ServicePlanningContext::world_version() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pinned_;
}

void ServicePlanningContext::same_world(std::uint64_t answered) const {
  if (pinned_ != 0 && answered != pinned_) {
    throw std::runtime_error("the node answered world version " + std::to_string(answered) + ", not the pinned " +
                             std::to_string(pinned_));
  }
}

std::uint64_t ServicePlanningContext::version_for_call() const {
  if (!pin_per_plan || pinned_ != 0) return pinned_;
  PinWorld srv;
  call(pin_, srv);
  pinned_ = srv.response.version;
  return pinned_;
}

bool ServicePlanningContext::state_valid(const double* v) const {
  CheckState srv;
  srv.request.state.name = group.names;
  srv.request.state.position.assign(v, v + group.size());
  srv.request.checks = checks;
  srv.request.tolerance = tolerance;
  std::lock_guard<std::mutex> lock(mutex_);
  srv.request.world_version = version_for_call();
  call(state_, srv);
  same_world(srv.response.world_version);
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
  srv.request.world_version = version_for_call();
  call(motion_, srv);
  same_world(srv.response.world_version);
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
  srv.request.world_version = version_for_call();
  call(motions_, srv);
  same_world(srv.response.world_version);
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
  srv.request.world_version = version_for_call();
  call(states_, srv);
  same_world(srv.response.world_version);
  if (srv.response.valid.size() != count) throw std::runtime_error("check_states answered for a different count");
  return std::vector<bool>(srv.response.valid.begin(), srv.response.valid.end());
}

bool ServicePlanningContext::check_state(const ompl::base::State* state) const {
  return state_valid(planning::state_values(state));
}

planning::MotionAnswer ServicePlanningContext::check_motion(const ompl::base::State* from, const ompl::base::State* to,
                                                            bool earliest) const {
  // The node certifies through its SceneChecker in earliest mode: the fraction comes either way.
  double fraction = 0.0;
  const bool free = motion_valid(planning::state_values(from), planning::state_values(to), earliest ? &fraction : nullptr);
  return {free, fraction};
}

std::vector<bool> ServicePlanningContext::check_motions(const std::vector<planning::StatePair>& motions) const {
  const std::size_t n = group.size();
  std::vector<double> starts, goals;
  starts.reserve(motions.size() * n);
  goals.reserve(motions.size() * n);
  for (const auto& [a, b] : motions) {
    starts.insert(starts.end(), planning::state_values(a), planning::state_values(a) + n);
    goals.insert(goals.end(), planning::state_values(b), planning::state_values(b) + n);
  }
  return motions_valid(starts.data(), goals.data(), motions.size());
}

}  // namespace bvh_collision
