#include "bvh_collision/robot/joint_state_history.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace bvh_collision {

JointStateHistory::JointStateHistory(const RobotModel& model, double horizon, double lead)
    : continuous_(model.variable_count(), 0), horizon_(horizon), lead_(lead) {
  if (!std::isfinite(horizon) || horizon < 0.0 || !std::isfinite(lead) || lead < 0.0) {
    throw std::invalid_argument("joint state history: the horizon and the lead must be finite and >= 0 s");
  }
  for (const RobotJoint& j : model.joints()) {
    if (j.variable >= 0 && j.type == JointType::kContinuous) continuous_[j.variable] = 1;
  }
}

void JointStateHistory::record(double time, const std::vector<double>& state) {
  if (!std::isfinite(time)) throw std::invalid_argument("joint state history: the time is not finite");
  if (state.size() != continuous_.size()) {
    throw std::invalid_argument("joint state history: " + std::to_string(state.size()) + " values for " +
                                std::to_string(continuous_.size()) + " variables");
  }
  // In time order; most states arrive last, so the search starts from the back.
  auto at = states_.end();
  while (at != states_.begin() && std::prev(at)->time > time) --at;
  if (at != states_.begin() && std::prev(at)->time == time) {
    std::prev(at)->state = state;
  } else {
    states_.insert(at, Stamped{time, state});
  }
  while (!states_.empty() && states_.front().time < states_.back().time - horizon_) states_.pop_front();
}

std::optional<std::vector<double>> JointStateHistory::at(double time) const {
  if (states_.empty() || !std::isfinite(time) || time < states_.front().time) return std::nullopt;
  if (time >= states_.back().time) {
    if (time > states_.back().time + lead_) return std::nullopt;
    return states_.back().state;
  }
  // The first state after `time`; the one before it is at or before `time`.
  const auto after = std::upper_bound(states_.begin(), states_.end(), time,
                                      [](double t, const Stamped& s) { return t < s.time; });
  const Stamped& b = *after;
  const Stamped& a = *std::prev(after);
  const double s = (time - a.time) / (b.time - a.time);
  std::vector<double> out(a.state.size());
  for (std::size_t i = 0; i < out.size(); ++i) {
    double delta = b.state[i] - a.state[i];
    // A continuous joint turns the short way between two close samples.
    if (continuous_[i]) delta = std::remainder(delta, 2.0 * M_PI);
    out[i] = a.state[i] + s * delta;
  }
  return out;
}

}  // namespace bvh_collision
