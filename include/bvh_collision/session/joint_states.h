// The robot's joint values as its joint-state messages bring them, without ROS: the current state
// (the neutral one until the first message), and the merged states at the messages' stamps
// (robot/joint_state_history.h), so that a cloud is filtered against the arm where it was when
// the cloud was taken, waiting a little for joint states that come after the cloud.
#pragma once

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "bvh_collision/robot/joint_state_history.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

class JointStates {
 public:
  // `neutral`: the state before any message; `horizon`, `lead` (s): JointStateHistory's. Throws
  // std::invalid_argument as JointStateHistory does.
  JointStates(const RobotModel& model, std::vector<double> neutral, double horizon, double lead);

  // Merges the values of `names` that are joints of the robot (with a variable) and finite,
  // ignoring the rest (joint states come from several publishers and other robots), and records
  // the merged state at `stamp` (s). `arrival` (s, the same clock as the timeouts the caller
  // keeps): when it came. False, and nothing recorded, when no value was the robot's. Throws
  // std::invalid_argument when names and positions differ in count.
  bool record(const std::vector<std::string>& names, const std::vector<double>& positions, double stamp, double arrival);

  std::vector<double> current() const;
  // When the last message that set a joint of ours arrived (nothing before the first).
  std::optional<double> last_arrival() const;
  // The state at `stamp` (s), waiting up to `timeout` (s) for the history to reach it; the
  // current state for a zero stamp or before any message; nothing when the stamp lies outside
  // the history.
  std::optional<std::vector<double>> at(double stamp, double timeout) const;
  std::uint64_t recorded() const;

 private:
  std::vector<std::pair<std::string, int>> variables_;  // joint name -> its variable, sorted by name
  mutable std::mutex mutex_;
  std::vector<double> state_;
  std::optional<double> last_arrival_;
  JointStateHistory history_;
  mutable std::condition_variable grew_;
  std::uint64_t recorded_ = 0;
};

}  // namespace bvh_collision
