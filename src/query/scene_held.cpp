// SceneChecker's held pairs: a self pair's clearance proven along the one variable of its path a
// motion moves (held_pair_clearance.h).
#include <algorithm>
#include <cmath>

#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/narrowphase/compound_shape.h"
#include "bvh_collision/query/scene_checker.h"
#include "held_pair_clearance.h"

namespace bvh_collision {
namespace {

// Exact tests a query may spend on stretches not yet tested: about what the motion's own intervals
// would spend on a pair held a few millimetres apart over a radian (an exact distance each).
constexpr int kTestsPerQuery = 256;
// Taken on top of every test's padding: the rounding of the test and of the kinematics, which
// pose the two links in the root's frame (a proof must not depend on the call that asked for it:
// it serves every later one).
constexpr double kTestMargin = 1e-6;

bool same_owner(const std::weak_ptr<const RobotCollisionModel>& a, const std::shared_ptr<const RobotCollisionModel>& b) {
  return !a.owner_before(b) && !b.owner_before(a);
}

// The joint whose value is variable v (not a mimic).
const RobotJoint* variable_joint(const RobotModel& robot, int v) {
  for (const RobotJoint& j : robot.joints()) {
    if (j.variable == v && j.mimic < 0) return &j;
  }
  return nullptr;
}

// Finite limits of a variable's joint (a continuous joint has none).
bool finite_limits(const RobotJoint* j) {
  return j != nullptr && j->bounded && std::isfinite(j->lower) && std::isfinite(j->upper) && j->upper > j->lower;
}

// The thread's trees, for this model and clearance (forgotten when either changed).
held_pair::HeldPairs& held_pairs(const std::shared_ptr<const RobotCollisionModel>& model, double need_extra, std::size_t pairs) {
  thread_local held_pair::HeldPairs cache;
  if (!same_owner(cache.model, model) || cache.need_extra != need_extra || cache.pairs.size() != pairs) {
    cache.model = model;
    cache.need_extra = need_extra;
    cache.pairs.assign(pairs, {});
  }
  return cache;
}

// May a held variable take this value under the motion rates? Within its joint's limits, or any
// value for a turning joint without them (a turn's rate does not depend on its angle; a slide's
// travel lengthens the chains below it, so a slide needs its limits).
bool held_within_limits(const RobotJoint* j, double value) {
  if (j == nullptr) return false;
  if (finite_limits(j)) return value >= j->lower && value <= j->upper;
  return j->type == JointType::kRevolute || j->type == JointType::kContinuous;
}

}  // namespace

bool SceneChecker::held_pair_clear(std::size_t p, const double* from, const double* to) const {
  const PairRates& rates = pair_rates_[p];
  if (!options_.held_pairs || !rates.path_of_variables) return false;
  int moving = -1;
  double rate = 0.0;
  for (const auto& [v, w] : rates.weights) {
    if (from[v] == to[v]) continue;
    if (moving >= 0) return false;  // two of the path's variables move
    moving = v, rate = w;
  }
  if (moving < 0) return false;
  const RobotCollisionModel& m = checker_.collision_model();
  held_pair::HeldPair& held = held_pairs(checker_.shared_collision_model(), options_.min_clearance, pair_rates_.size()).pairs[p];
  bool same = held.variable == moving && held.held.size() == rates.weights.size();
  for (std::size_t k = 0; k < rates.weights.size() && same; ++k) {
    const int v = rates.weights[k].first;
    same = held.held[k] == (v == moving ? 0.0 : from[v]);
  }
  if (!same) {
    // The rates hold within the limits: a held value beyond its joint's (a prismatic joint's
    // travel lengthens the chains below it) gets no tree, nor a moving joint without limits.
    const RobotModel& robot = checker_.model();
    const RobotJoint* joint = variable_joint(robot, moving);
    if (!finite_limits(joint)) return false;
    held.variable = -1;
    held.held.resize(rates.weights.size());
    for (std::size_t k = 0; k < rates.weights.size(); ++k) {
      const int v = rates.weights[k].first;
      const RobotJoint* other = variable_joint(robot, v);
      if (v != moving && !held_within_limits(other, from[v])) return false;
      held.held[k] = v == moving ? 0.0 : from[v];
    }
    held.variable = moving;
    held.tree.reset(joint->lower, joint->upper, rate);
  }
  const int a = m.checked_pairs()[p].first, b = m.checked_pairs()[p].second;  // (a lambda takes them: not bound)
  thread_local std::vector<double> state;
  thread_local std::vector<Transform> poses;
  state.assign(from, from + checker_.model().variable_count());
  const double need = m.paddings()[a] + m.paddings()[b] + options_.min_clearance + kTestMargin;
  const CompoundShape ca = m.compound(a), cb = m.compound(b);
  return held.tree.clear(std::min(from[moving], to[moving]), std::max(from[moving], to[moving]), kTestsPerQuery,
                         [&](double c, double h) {
                           state[moving] = c;
                           m.kinematics().compute(state.data(), poses);
                           PairRequest request;
                           request.padding = need + rate * h;
                           QueryStats stats;
                           return compounds_collide(ca, poses[a], cb, poses[b], request, nullptr, stats);
                         });
}

}  // namespace bvh_collision
