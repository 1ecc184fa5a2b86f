// OMPL through the node: a StateValidityChecker and a MotionValidator that ask a running
// collision_checker over its services (check_state, certified check_motion), a batch check of
// many states in one check_states call, and of many motions in one check_motions call. The twins of planning/ompl_validity.h for a planner in
// another process or on another machine; persistent connections (a new connection per call costs
// more than the check). Joints outside the group take the node's current joint_states.
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

 private:
  mutable std::mutex mutex_;  // one call at a time per connection
  mutable ros::ServiceClient state_, states_, motion_, motions_;
};

class ServiceStateValidityChecker : public ompl::base::StateValidityChecker {
 public:
  ServiceStateValidityChecker(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<const ServicePlanningContext> context);
  bool isValid(const ompl::base::State* state) const override;

 private:
  std::shared_ptr<const ServicePlanningContext> context_;
};

class ServiceMotionValidator : public ompl::base::MotionValidator {
 public:
  ServiceMotionValidator(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<const ServicePlanningContext> context);
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2) const override;
  bool checkMotion(const ompl::base::State* s1, const ompl::base::State* s2,
                   std::pair<ompl::base::State*, double>& last_valid) const override;
  // Several motions in one call (check_motions), for a caller that has them at once: a lazy
  // planner's candidate path, a path's segments to certify.
  std::vector<bool> checkMotions(const std::vector<std::pair<const ompl::base::State*, const ompl::base::State*>>& motions) const;

 private:
  std::shared_ptr<const ServicePlanningContext> context_;
};

}  // namespace bvh_collision
