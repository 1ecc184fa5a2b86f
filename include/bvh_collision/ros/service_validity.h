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
  ~ServicePlanningContext();  // releases its pinned world
  ServicePlanningContext(const ServicePlanningContext&) = delete;
  ServicePlanningContext& operator=(const ServicePlanningContext&) = delete;

  planning::JointGroup group;
  std::uint8_t checks = 3;  // CheckState::SELF | CheckState::ENVIRONMENT
  double tolerance = 0.0;   // check_state and check_states (check_motion: the node's ~tolerance)
  std::shared_ptr<planning::ValidityCounters> counters = std::make_shared<planning::ValidityCounters>();
  // One world for one plan: by default the first call pins the node's current world version
  // (pin_world) and every call after it, the final path's re-check too, answers against that
  // world while clouds change the node's map, until new_plan() (the next call pins the world then
  // current) or the context goes away. A pin left unused for the node's ~pin_timeout expires: the
  // next call throws, naming it. False: every call asks the latest world.
  bool pin_per_plan = true;
  void new_plan();
  std::uint64_t world_version() const;  // the version pinned (0: none yet)

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
  // The version a call names (pinning one first when pin_per_plan asks); with mutex_ held.
  std::uint64_t version_for_call() const;
  void same_world(std::uint64_t answered) const;  // throws unless the pinned version answered
  void release() const;
  mutable std::mutex mutex_;  // one call at a time per connection
  mutable ros::ServiceClient state_, states_, motion_, motions_, pin_;
  mutable std::uint64_t pinned_ = 0;
};

using ServiceStateValidityChecker = planning::StateValidity<ServicePlanningContext>;
using ServiceMotionValidator = planning::MotionValidity<ServicePlanningContext>;

}  // namespace bvh_collision
