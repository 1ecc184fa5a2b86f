// CollisionChecker along a motion: the straight joint-space segment between two states, checked
// at a fixed joint step or certified by conservative advancement (each step shorter than the
// clearance divided by a bound on how fast any point of any link moves).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/limits.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"

namespace bvh_collision {

// A slide beyond its travel lengthens every lever above it by at most |multiplier| times the
// excess, which is largest at an end of the segment (|value| is convex along it).
double CollisionChecker::link_speed(int link, const double* start, const double* goal) const {
  const auto& rates = m_->motion_rates()[link];
  double speed = 0.0, turning = 0.0;
  for (std::size_t j = 0; j < rates.size(); ++j) {
    const double change = std::abs(goal[j] - start[j]);
    speed += rates[j] * change;
    turning += m_->motion_turns()[link][j] * change;
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
  const bool lanes = proxies != nullptr && !proxies->batch.empty();
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
      proxies->batch.check(checker.accelerators().pair_clearance(), block.data(), count, request.tolerance, self_hit);
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

// Clearance of one state: its distance to everything checked, less the padding (nullopt when the
// state collides). A self pair's padding is the sum of its links' paddings.
std::optional<double> clearance(const CollisionChecker& checker, const double* state, const Environment& env,
                                const MotionRequest& request, double max_padding) {
  double gap = std::numeric_limits<double>::infinity();
  if (request.self) {
    SelfCollisionRequest r;
    r.distance = true;
    const SelfCollisionResult result = checker.check_self(state, r);
    if (result.collision) return std::nullopt;
    if (std::isfinite(result.min_distance)) gap = std::min(gap, result.min_distance - 2.0 * max_padding);
  }
  if (request.environment) {
    EnvironmentRequest r;
    r.distance = true;
    r.root_pose = request.root_pose;
    const EnvironmentResult result = checker.check_environment(state, env, r);
    if (result.collision) return std::nullopt;
    if (std::isfinite(result.min_distance)) gap = std::min(gap, result.min_distance - max_padding);
  }
  return gap;
}

// A clearance bound may be this fraction loose where it exceeds the stop (the step shrinks by at
// most 1 / 1.25): far pairs and links then cost a few sphere tests instead of a walk to the
// leaves, while a bound at the stop is the leaves' own (ProxySlack).
constexpr double kClearanceSlack = 0.25;

}  // namespace

// Per self pair and link, the cheapest bound first (bounding spheres, the pair's clearance grid,
// the distance field), the proxies only where those do not already exceed the smallest gap found.
double CollisionChecker::proxy_clearance(const double* state, const Environment& env, const MotionRequest& request,
                                         const ProxyLevel& proxies, const OctreeDistanceField* field, double stop) const {
  thread_local std::vector<Transform> poses;
  m_->kinematics().compute(state, poses);
  const auto centre = [&](std::size_t l) { return Vec3(poses[l] * m_->bounds()[l].center); };
  const auto margin = [&](std::size_t l) { return pose_margin(poses[l].t.norm() + m_->bounds()[l].center.norm() + m_->bounds()[l].radius); };
  double gap = std::numeric_limits<double>::infinity();
  if (request.self) {
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t p = 0; p < m_->checked_pairs().size(); ++p) {
      const auto [a, b] = m_->checked_pairs()[p];
      const double pads = m_->paddings()[a] + m_->paddings()[b];
      order.emplace_back((centre(a) - centre(b)).norm() - m_->bounds()[a].radius - m_->bounds()[b].radius - pads -
                             margin(a) - margin(b), p);
    }
    std::sort(order.begin(), order.end());
    for (const auto& [bound, p] : order) {
      if (bound >= gap) break;
      const auto [a, b] = m_->checked_pairs()[p];
      const double pads = m_->paddings()[a] + m_->paddings()[b];
      if (a_->pair_clearance().lower_bound(p, state) - pads >= gap) continue;
      gap = proxies_distance(proxies.links[a], poses[a], proxies.links[b], poses[b], gap + pads,
                             ProxySlack{kClearanceSlack, stop + pads}) - pads;
      if (gap <= stop) return gap;
    }
  }
  if (!request.environment) return gap;
  const Octree& tree = env.octree();
  for (std::size_t l = 0; l < m_->shapes().size(); ++l) {
    if (m_->shapes()[l].empty()) continue;
    const Transform pose = request.root_pose * poses[l];
    const double padding = m_->paddings()[l];
    const double radius = m_->bounds()[l].radius + pose_margin(pose.t.norm() + m_->bounds()[l].center.norm() + m_->bounds()[l].radius);
    if (!tree.empty() && !(field != nullptr && field->lower_bound(pose * m_->bounds()[l].center) - radius - padding >= gap)) {
      gap = proxy_obstacle_distance(proxies.links[l], pose, gap + padding, [&](const Vec3& c, double r, double best) {
              if (field != nullptr) {
                const double bound = field->lower_bound(c) - r;
                if (bound >= best) return bound;
              }
              return std::max(0.0, point_octree_distance(c, tree, best + r).distance - r);
            }, ProxySlack{kClearanceSlack, stop + padding}) - padding;
      if (gap <= stop) return gap;
    }
    for (std::size_t o = 0; o < env.objects().size(); ++o) {
      if (env.object_allowed(m_->robot().links()[l].name, o)) continue;
      const CollisionObject& object = env.objects()[o];
      const double apart = (pose * m_->bounds()[l].center - object.pose * object.bound_center).norm() - radius -
                           object.bound_radius - padding;
      if (apart >= gap) continue;
      const ShapeRef obstacle = shape_of(object);
      QueryStats stats;
      gap = proxy_obstacle_distance(proxies.links[l], pose, gap + padding, [&](const Vec3& c, double r, double best) {
              Vec3 wa, wb;
              return shapes_distance({nullptr, nullptr, Primitive::sphere(r)}, Transform{Mat3::Identity(), c},
                                             obstacle, object.pose, best, true, wa, wb, stats);
            }, ProxySlack{kClearanceSlack, stop + padding}) - padding;
      if (gap <= stop) return gap;
    }
  }
  return gap;
}

namespace {

// Conservative advancement. Over a step ds every point of link L moves at most ds * M_L, with
// M_L = sum_j rate(L, j) |delta_j|; a self pair closes by at most ds (M_a + M_b), an obstacle gap
// by ds M_L. With M the largest M_L, a step below gap / (2 M) cannot hide a collision.
MotionResult motion_certified(const CollisionChecker& checker, Segment& segment, const Environment& env,
                              const MotionRequest& request) {
  MotionResult result;
  double speed = 0.0, max_padding = 0.0;
  for (std::size_t l = 0; l < checker.model().links().size(); ++l) {
    speed = std::max(speed, checker.link_speed(static_cast<int>(l), segment.start(), segment.goal()));
    max_padding = std::max(max_padding, checker.link_padding(static_cast<int>(l)));
  }
  const double closing = (request.self ? 2.0 : 1.0) * speed;
  // At a tolerance t, a lower bound on the clearance that is at most e below it (the proxies of
  // level e) serves as well: a state whose bound is at most t - e is within t of collision. The
  // coarsest level up to t / 2 leaves at least t / 2 of that room (so the steps near a contact
  // stay long); failing that, up to t, with min_clearance as the room.
  ToleranceQuestion question{request.tolerance, Counterpart::kLink};
  question.motion = true;
  const ProxyUse use = proxy_use(question);
  const ProxyLevel* proxies = checker.accelerators().proxies_for(use.prefer_up_to);
  if (proxies == nullptr) proxies = checker.accelerators().proxies_for(use.decide_up_to);
  const double stop = proxies ? std::max(request.tolerance - proxies->level, request.min_clearance)
                              : std::max(request.tolerance, request.min_clearance);
  const auto field = proxies && request.environment ? checker.kept_distance_field(env, request.root_pose) : nullptr;
  double s = 0.0;
  while (result.states_checked < request.max_states) {
    ++result.states_checked;
    const double* q = segment.at(s);
    const auto gap = proxies ? std::optional<double>(checker.proxy_clearance(q, env, request, *proxies, field.get(), stop))
                             : clearance(checker, q, env, request, max_padding);
    if (!gap || *gap <= stop) {
      // In collision, or within the tolerance of it (allowed to count as collision).
      result.certified = true;
      result.colliding_fraction = s;
      return result;
    }
    result.last_valid_fraction = s;
    if (s >= 1.0) {
      result.valid = result.certified = true;
      return result;
    }
    // 0.99: the clearance and the rates are exact bounds; leave room for their rounding.
    s = closing > 0.0 ? std::min(1.0, s + 0.99 * *gap / closing) : 1.0;
  }
  result.message = "not certified after " + std::to_string(request.max_states) + " states: the motion passes within " +
                   "rounding of a collision at fraction " + std::to_string(result.last_valid_fraction);
  return result;
}

}  // namespace

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
  Segment segment(start, goal, m_->robot().variable_count());
  return request.resolution > 0.0 ? motion_in_steps(*this, segment, env, request)
                                  : motion_certified(*this, segment, env, request);
}

}  // namespace bvh_collision
