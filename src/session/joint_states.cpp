// The robot's joint values from its joint-state messages (session/joint_states.h).
#include "bvh_collision/session/joint_states.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

namespace bvh_collision {

JointStates::JointStates(const RobotModel& model, std::vector<double> neutral, double horizon, double lead)
    : state_(std::move(neutral)), history_(model, horizon, lead) {
  for (const RobotJoint& j : model.joints()) {
    if (j.variable >= 0) variables_.emplace_back(j.name, j.variable);
  }
  std::sort(variables_.begin(), variables_.end());
}

bool JointStates::record(const std::vector<std::string>& names, const std::vector<double>& positions, double stamp,
                         double arrival) {
  if (names.size() != positions.size()) {
    throw std::invalid_argument("joint states with " + std::to_string(names.size()) + " names and " +
                                std::to_string(positions.size()) + " positions");
  }
  std::lock_guard<std::mutex> lock(mutex_);
  bool ours = false;
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto it = std::lower_bound(variables_.begin(), variables_.end(), std::make_pair(names[i], -1));
    if (it == variables_.end() || it->first != names[i] || !std::isfinite(positions[i])) continue;
    state_[static_cast<std::size_t>(it->second)] = positions[i];
    ours = true;
  }
  if (!ours) return false;
  last_arrival_ = arrival;
  history_.record(stamp, state_);
  ++recorded_;
  grew_.notify_all();
  return true;
}

std::vector<double> JointStates::current() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return state_;
}

std::optional<double> JointStates::last_arrival() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return last_arrival_;
}

std::optional<std::vector<double>> JointStates::at(double stamp, double timeout) const {
  std::unique_lock<std::mutex> lock(mutex_);
  if (stamp == 0.0 || history_.empty()) return state_;
  grew_.wait_for(lock, std::chrono::duration<double>(timeout), [&] { return history_.newest() >= stamp; });
  return history_.at(stamp);
}

std::uint64_t JointStates::recorded() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return recorded_;
}

}  // namespace bvh_collision
