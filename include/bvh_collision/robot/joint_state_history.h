// The robot's joint values over the last seconds, to place the robot at the moment a sensor saw
// it: a camera cloud stamped 100 ms ago must be filtered against the arm where it was
// then, not where it is now, or the arm's own points stay as obstacles (a ghost it then collides
// with) and real points near its present pose are dropped.
//
// States are recorded with their time (seconds, any epoch) in time order; `at(t)` interpolates
// linearly between the two recorded states around t, a continuous joint the short way round.
// A time before the oldest state kept, or after the newest by more than `lead`, has no answer:
// the robot's pose then is not known.
#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

class JointStateHistory {
 public:
  // `horizon` (s): how long states are kept; `lead` (s): how far past the newest state a time may
  // lie and still take it. Throws std::invalid_argument for a negative or non-finite value.
  JointStateHistory(const RobotModel& model, double horizon, double lead);

  // Records the full state (variable_count() values) at `time`. States older than the newest
  // by more than the horizon are forgotten. Out-of-order times are placed in order; a time equal
  // to one kept replaces it. Throws std::invalid_argument for a wrong size or a non-finite time.
  void record(double time, const std::vector<double>& state);

  // The state at `time`, or nothing when it lies outside [oldest, newest + lead] (or nothing is
  // recorded).
  std::optional<std::vector<double>> at(double time) const;

  bool empty() const { return states_.empty(); }
  std::size_t size() const { return states_.size(); }
  double oldest() const { return states_.front().time; }  // only when not empty
  double newest() const { return states_.back().time; }

 private:
  struct Stamped {
    double time;
    std::vector<double> state;
  };
  std::vector<char> continuous_;  // per variable: a continuous joint (angles wrap)
  double horizon_, lead_;
  std::deque<Stamped> states_;
};

}  // namespace bvh_collision
