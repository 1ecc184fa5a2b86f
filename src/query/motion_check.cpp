// CollisionChecker along a motion: the straight joint-space segment between two states, checked
// at a fixed joint step, or certified by the prepared scene's interval engine (scene_checker.h).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/geometry/limits.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"

namespace bvh_collision {

// A slide beyond its travel lengthens every lever above it by at most |multiplier| times the
// excess, which is largest at an end of the segment (|value| is convex along it).
double CollisionChecker::link_speed(int link, const double* start, const double* goal) const {
  // (The variables that do not move the link add zeros: skipped, the sums are the same bits.)
  double speed = 0.0, turning = 0.0;
  for (const MotionTerm& term : m_->motion_terms()[link]) {
    const double change = std::abs(goal[term.variable] - start[term.variable]);
    speed += term.rate * change;
    turning += term.turn * change;
  }
  double excess = 0.0;
  for (const SlideBound& slide : m_->motion_slides()[link]) {
    const double farthest = std::max(std::abs(start[slide.variable]), std::abs(goal[slide.variable]));
    excess += slide.multiplier * std::max(0.0, farthest - slide.travel);
  }
  return speed + excess * turning;
}

namespace {

// The segment's states: start + s * (goal - start), the goal itself at s = 1.
class Segment {
 public:
  Segment(const double* start, const double* goal, std::size_t n) : start_(start), goal_(goal), delta_(n), state_(n) {
    for (std::size_t j = 0; j < n; ++j) delta_[j] = goal[j] - start[j];
  }
  const double* at(double s) {
    for (std::size_t j = 0; j < delta_.size(); ++j) state_[j] = s >= 1.0 ? goal_[j] : start_[j] + s * delta_[j];
    return state_.data();
  }
  const std::vector<double>& delta() const { return delta_; }
  const double* start() const { return start_; }
  const double* goal() const { return goal_; }
  double longest() const {
    double m = 0.0;
    for (double d : delta_) m = std::max(m, std::abs(d));
    return m;
  }

 private:
  const double* start_;
  const double* goal_;
  std::vector<double> delta_, state_;
};

bool collides_with_environment(const CollisionChecker& checker, const double* state, const Environment& env,
                               const MotionRequest& request) {
  if (!request.environment) return false;
  EnvironmentRequest r;
  r.tolerance = request.tolerance;
  r.root_pose = request.root_pose;
  r.distance_field = EnvironmentRequest::DistanceField::kIfKept;  // one already built for this octree
  r.contacts = false;
  return checker.check_environment(state, env, r).collision;
}

// The states in order, the first colliding one ends the motion. Where a proxy level fits the
// tolerance, self checks run on blocks of states in the SIMD lanes (model/proxy_batch.h), the
// same answers as one state at a time.
MotionResult motion_in_steps(const CollisionChecker& checker, Segment& segment, const Environment& env,
                             const MotionRequest& request) {
  MotionResult result;
  // Counted in floating point first: 3 rad at 1e-300 rad is not a number of states to cast.
  const double needed = std::max(1.0, std::ceil(segment.longest() / request.resolution));
  char what[160];
  std::snprintf(what, sizeof what, "a fixed-step motion of %g rad (or m) at resolution %g with its states",
                segment.longest(), request.resolution);
  check_limit(what,
              needed + 1.0, checker.collision_model().limits().motion_states, "max_motion_states");
  const auto steps = static_cast<std::size_t>(needed);
  const ProxyLevel* proxies =
      request.self ? checker.accelerators().proxies_for(proxy_use({request.tolerance, Counterpart::kLink}).decide_up_to) : nullptr;
  const bool lanes = proxies != nullptr && proxies->in_lanes();
  constexpr std::size_t kBlock = 16;
  const std::size_t n = checker.model().variable_count();
  std::vector<double> block(lanes ? kBlock * n : 0);
  char self_hit[kBlock] = {};
  for (std::size_t first = 0; first <= steps; first += kBlock) {
    const std::size_t count = std::min(kBlock, steps + 1 - first);
    if (lanes) {
      for (std::size_t k = 0; k < count; ++k) {
        const double* q = segment.at(static_cast<double>(first + k) / static_cast<double>(steps));
        std::copy(q, q + n, block.begin() + static_cast<std::ptrdiff_t>(k * n));
      }
      checker.check_self_in_lanes(*proxies, block.data(), count, request.tolerance, self_hit);
    }
    for (std::size_t k = 0; k < count; ++k) {
      const double s = static_cast<double>(first + k) / static_cast<double>(steps);
      ++result.states_checked;
      const double* q = lanes ? block.data() + k * n : segment.at(s);
      const bool self = lanes ? self_hit[k] != 0
                              : request.self && checker.check_self(q, SelfCollisionRequest{request.tolerance}).collision;
      if (self || collides_with_environment(checker, q, env, request)) {
        result.colliding_fraction = s;
        return result;
      }
      result.last_valid_fraction = s;
    }
  }
  result.valid = true;
  return result;
}

}  // namespace

// The kept scene when it was prepared for this snapshot and these options, else a new one (the
// old one stays with the motions still running on it).
std::shared_ptr<const SceneChecker> CollisionChecker::prepared_scene(const Environment& env, const MotionRequest& request) const {
  SceneCheckOptions options;
  options.self = request.self;
  options.environment = request.environment;
  options.tolerance = request.tolerance;
  options.root_pose = request.root_pose;
  options.min_clearance = request.min_clearance;
  options.max_intervals = request.max_states;
  const auto same = [&](const SceneChecker& s) {
    const SceneCheckOptions& o = s.options();
    return s.environment().same_snapshot(env) && o.self == options.self && o.environment == options.environment &&
           o.tolerance == options.tolerance && o.root_pose.R == options.root_pose.R && o.root_pose.t == options.root_pose.t &&
           o.min_clearance == options.min_clearance && o.max_intervals == options.max_intervals;
  };
  std::lock_guard<std::mutex> lock(prepared_->mutex);
  if (!prepared_->scene || !same(*prepared_->scene)) {
    // The scene gets a copy of this checker without the kept scene: it would hold itself.
    CollisionChecker own(m_, a_);
    prepared_->scene = std::make_shared<const SceneChecker>(own, std::make_shared<const Environment>(env), options);
  }
  return prepared_->scene;
}

MotionResult CollisionChecker::check_motion(const double* start, const double* goal, const Environment& env,
                                            const MotionRequest& request) const {
  require_carried(env);
  if (!std::isfinite(request.resolution) || request.resolution < 0.0) {
    throw std::invalid_argument("motion check: resolution must be finite and >= 0");
  }
  if (!std::isfinite(request.tolerance) || request.tolerance < 0.0) {
    throw std::invalid_argument("motion check: tolerance must be finite and >= 0");
  }
  if (!std::isfinite(request.min_clearance) || request.min_clearance < 0.0) {
    throw std::invalid_argument("motion check: min_clearance must be finite and >= 0");
  }
  require_finite_state(start, "motion check");
  require_finite_state(goal, "motion check");
  if (request.resolution == 0.0) return prepared_scene(env, request)->check_motion(start, goal, true);
  Segment segment(start, goal, m_->robot().variable_count());
  return motion_in_steps(*this, segment, env, request);
}

}  // namespace bvh_collision
