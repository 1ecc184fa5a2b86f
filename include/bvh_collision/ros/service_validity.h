// OMPL through the node: the context of planning/ompl_validity.h's validators that asks a running
// collision_checker over its services (check_state, certified check_motion), a batch check of
// many states in one check_states call, and of many motions in one check_motions call: for a
// planner in another process or on another machine. Persistent connections (a new connection per
// call costs more than the check). Joints outside the group take the node's current joint_states.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ros/node_handle.h>
#include <ros/service_client.h>

#include "bvh_collision/planning/ompl_validity.h"

namespace bvh_collision {

struct ServicePlanningContext {
  // `checker` is the node's namespace ("/collision_checker"); `timeout` how long to wait for its
  // services here. Throws std::runtime_error when they do not appear.
  ServicePlanningContext(const std::string& checker, planning::JointGroup group, double timeout = 10.0);

  planning::JointGroup group;
  std::uint8_t checks = 3;  // CheckState::SELF | CheckState::ENVIRONMENT
  double tolerance = 0.0;   // check_state and check_states (check_motion: the node's ~tolerance)
  std::shared_ptr<planning::ValidityCounters> counters = std::make_shared<planning::ValidityCounters>();

  // Throw std::runtime_error when a call fails or the node answers an error.
  bool state_valid(const double* values) const;
  // Certified (resolution 0); `last_valid_fraction` may be null.
  bool motion_valid(const double* start, const double* goal, double* last_valid_fraction = nullptr) const;
  // `count` states of group.size() values each, row by row: one call.
  std::vector<bool> states_valid(const double* values, std::size_t count) const;
  // `count` motions (starts and goals row by row, group.size() values each), each certified:
  // one check_motions call; `last_valid_fractions` may be null.
  std::vector<bool> motions_valid(const double* starts, const double* goals, std::size_t count,
                                  std::vector<double>* last_valid_fractions = nullptr) const;

  // The validators' questions (planning::StateValidity, planning::MotionValidity), as above.
  bool check_state(const ompl::base::State* state) const;
  planning::MotionAnswer check_motion(const ompl::base::State* from, const ompl::base::State* to, bool earliest) const;
  std::vector<bool> check_motions(const std::vector<planning::StatePair>& motions) const;

 private:
  mutable std::mutex mutex_;  // one call at a time per connection
  mutable ros::ServiceClient state_, states_, motion_, motions_;
};

using ServiceStateValidityChecker = planning::StateValidity<ServicePlanningContext>;
using ServiceMotionValidator = planning::MotionValidity<ServicePlanningContext>;

}  // namespace bvh_collision
