#include "bvh_collision/query/collision_checker.h"

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"
#include "bvh_collision/query/motion_calibration.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>

namespace bvh_collision {
namespace {

// The pair indices a self query visits: a request's own list (validated), or 0 .. count - 1.
class PairIndices {
 public:
  PairIndices(const std::vector<std::size_t>* only, std::size_t count) : only_(only), count_(count) {
    if (only_) {
      for (const std::size_t p : *only_) {
        if (p >= count_) throw std::out_of_range("only_pairs: pair index " + std::to_string(p) + " of " + std::to_string(count_));
      }
    }
  }
  struct Iterator {
    const std::vector<std::size_t>* only;
    std::size_t i;
    std::size_t operator*() const { return only ? (*only)[i] : i; }
    Iterator& operator++() { return ++i, *this; }
    bool operator!=(const Iterator& o) const { return i != o.i; }
  };
  Iterator begin() const { return {only_, 0}; }
  Iterator end() const { return {only_, only_ ? only_->size() : count_}; }

 private:
  const std::vector<std::size_t>* only_;
  std::size_t count_;
};

// A self check's scratch, per thread. Reached through a call the compiler cannot see into: in a
// shared library each use of a thread_local is a call to __tls_get_addr, and GCC re-derives the
// address at every use rather than keep it (dozens of calls a check).
struct SelfScratch {
  std::vector<Transform> poses;
  std::vector<Vec3> centers;
  std::vector<std::pair<double, std::size_t>> order;
};
[[gnu::noinline]] SelfScratch& self_scratch() {
  thread_local SelfScratch scratch;
  return scratch;
}

}  // namespace

CollisionChecker::CollisionChecker(RobotModel model, AllowedCollisionMatrix acm, const CheckerOptions& options)
    : m_(std::make_shared<const RobotCollisionModel>(std::move(model), std::move(acm), options)),
      a_(calibrated(m_, std::make_shared<RobotAccelerators>(*m_, options))) {}

CollisionChecker CollisionChecker::with_proxy_level(double level, const std::atomic<bool>* cancel) const {
  return CollisionChecker(m_, calibrated(m_, std::make_shared<RobotAccelerators>(a_->with_proxy_level(*m_, level, cancel))));
}

CollisionChecker CollisionChecker::with_pair_clearance(std::size_t cells) const {
  return CollisionChecker(m_, calibrated(m_, std::make_shared<RobotAccelerators>(a_->with_pair_clearance(*m_, cells))));
}

std::shared_ptr<const RobotAccelerators> CollisionChecker::calibrated(const std::shared_ptr<const RobotCollisionModel>& model,
                                                                      std::shared_ptr<RobotAccelerators> accelerators) {
  if (accelerators->calibrates() && accelerators->proxy_levels().size() >= 2) {
    // (The checker timed holds the accelerators only while it is timed: they are set once it is gone.)
    const double growth = choose_pair_exact_growth(CollisionChecker(model, accelerators)).growth;
    accelerators->set_pair_exact_growth(growth);
  }
  return accelerators;
}

bool CollisionChecker::pair_collides(int a, int b, const std::vector<Transform>& poses,
                                     const SelfCollisionRequest& request, SelfCollisionResult& result) const {
  PairRequest pair;
  pair.padding = m_->paddings()[a] + m_->paddings()[b];
  pair.tolerance = request.tolerance;
  pair.max_contacts = request.max_contacts;
  pair.solids = request.solids;
  std::vector<MeshContact> contacts;
  const bool hit = compounds_collide(m_->compound(a), poses[a], m_->compound(b), poses[b], pair,
                                     request.max_contacts > 0 ? &contacts : nullptr, result.stats);
  for (const MeshContact& c : contacts) result.contacts.push_back({a, b, c});
  return hit;
}

CollisionChecker CollisionChecker::carrying(const std::vector<AttachedBody>& bodies, const NamedAllowedCollisions& allowed,
                                            bool proxies) const {
  if (bodies.empty()) return *this;
  auto model = std::make_shared<const RobotCollisionModel>(m_->carrying(bodies, allowed));
  auto accelerators = std::make_shared<const RobotAccelerators>(a_->carrying(*model, proxies));
  return CollisionChecker(std::move(model), std::move(accelerators));
}

double CollisionChecker::pair_distance(int a, int b, const std::vector<Transform>& poses, double best,
                                       const SelfCollisionRequest& request, SelfCollisionResult& result) const {
  Vec3 wa, wb;
  const double d = compounds_distance(m_->compound(a), poses[a], m_->compound(b), poses[b], best, request.solids, wa, wb,
                                      result.stats, request.tolerance);
  if (!(d < best)) return best;
  result.min_distance = d;
  result.closest_a = a;
  result.closest_b = b;
  result.point_a = wa;
  result.point_b = wb;
  return d;
}

namespace {

// Are all n values finite? (Their sum times zero is a NaN when one is not: inf * 0 is one.)
bool all_finite(const double* values, std::size_t n) {
  double zero = 0.0;
  for (std::size_t j = 0; j < n; ++j) zero += values[j] * 0.0;
  return zero == 0.0;
}

}  // namespace

void CollisionChecker::require_finite_state(const double* state, const char* what) const {
  const std::size_t n = m_->robot().variable_count();
  if (all_finite(state, n)) return;  // the names only on failure
  for (std::size_t j = 0; j < n; ++j) {
    if (!std::isfinite(state[j])) throw std::invalid_argument(std::string(what) + ": " + m_->robot().variable_names()[j] + " is not finite");
  }
}

SelfCollisionResult CollisionChecker::check_self(const double* state, const SelfCollisionRequest& request) const {
  require_finite_state(state, "self check");
  SelfCollisionResult result;
  SelfScratch& scratch = self_scratch();
  std::vector<Transform>& poses = scratch.poses;
  m_->kinematics().compute(state, poses);
  // Broad phase: the gap between the links' bounding spheres, a lower bound on their distance.
  std::vector<Vec3>& centers = scratch.centers;
  centers.resize(poses.size());
  for (std::size_t l = 0; l < poses.size(); ++l) {
    const LinkBound& bound = m_->bounds()[l];
    if (bound.radius < 0) continue;
    const Mat3& r = poses[l].R;
    const Vec3& c = bound.center;
    for (int i = 0; i < 3; ++i) centers[l][i] = r(i, 0) * c[0] + r(i, 1) * c[1] + r(i, 2) * c[2] + poses[l].t[i];
  }
  std::vector<std::pair<double, std::size_t>>& order = scratch.order;
  order.clear();
  if (!request.distance) {
    // Collision only: the pairs whose spheres come within reach, deepest overlap (relative to
    // the reach) first, because those collide most often and a boolean query stops at the first.
    for (const std::size_t p : PairIndices(request.only_pairs, m_->checked_pairs().size())) {
      const auto [a, b] = m_->checked_pairs()[p];
      // Not grown by the tolerance: a pair farther apart than its padding may be answered free at
      // every tolerance (narrowphase/tolerance_policy.h), so a tolerance adds no pair.
      const double reach = m_->bounds()[a].radius + m_->bounds()[b].radius + m_->paddings()[a] + m_->paddings()[b];
      const double d2 = (centers[a] - centers[b]).squaredNorm();
      if (d2 <= reach * reach) order.emplace_back(d2 / (reach * reach), p);
    }
    if (!request.all_pairs) std::sort(order.begin(), order.end());
    // At a tolerance a proxy level fits (narrowphase/tolerance_policy.h), the proxies answer alone:
    // apart means the links are apart, overlapping means they are within padding + level.
    ToleranceQuestion question{request.tolerance, Counterpart::kLink};
    question.boolean = request.max_contacts == 0;
    question.solids = request.solids;
    const ProxyLevel* proxies = a_->proxies_for(proxy_use(question).decide_up_to);
    for (const auto& [key, p] : order) {
      const auto [a, b] = m_->checked_pairs()[p];
      // A pair whose proven clearance in this state exceeds its padding cannot collide and has
      // no contact (model/pair_clearance.h).
      if (a_->pair_clearance().lower_bound(p, state) > m_->paddings()[a] + m_->paddings()[b]) continue;
      ++result.stats.pair_tests;
      const bool hit = proxies && proxies->answers(p) ? proxies_overlap(proxies->links[a], poses[a], proxies->links[b], poses[b],
                                                 m_->paddings()[a] + m_->paddings()[b])
                               : pair_collides(a, b, poses, request, result);
      if (hit) {
        result.collision = true;
        result.colliding_pairs.emplace_back(a, b);
        if (!request.all_pairs) break;
      }
    }
    return result;
  }
  // Distance: nearest pairs first, so that a small bound prunes the rest early.
  for (const std::size_t p : PairIndices(request.only_pairs, m_->checked_pairs().size())) {
    const auto [a, b] = m_->checked_pairs()[p];
    order.emplace_back((centers[a] - centers[b]).norm() - m_->bounds()[a].radius - m_->bounds()[b].radius, p);
  }
  std::sort(order.begin(), order.end());
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [gap, p] : order) {
    const auto [a, b] = m_->checked_pairs()[p];
    const bool may_collide = gap <= m_->paddings()[a] + m_->paddings()[b];
    if (may_collide && (request.all_pairs || !result.collision) && (++result.stats.pair_tests, pair_collides(a, b, poses, request, result))) {
      result.collision = true;
      result.colliding_pairs.emplace_back(a, b);
    }
    if (gap < best - request.tolerance) best = pair_distance(a, b, poses, best, request, result);
  }
  if (!std::isfinite(best)) result.min_distance = std::numeric_limits<double>::infinity();
  return result;
}

std::vector<bool> CollisionChecker::check_self_batch(const double* states, std::size_t count, double tolerance) const {
  BatchRequest request;
  request.environment = false;
  request.tolerance = tolerance;
  const std::vector<char> out = check_batch(states, count, nullptr, request);
  return std::vector<bool>(out.begin(), out.end());
}

void CollisionChecker::check_self_in_lanes(const ProxyLevel& proxies, const double* states, std::size_t count, double tolerance,
                                           char* out, SimdPath path) const {
  proxies.batch.check(a_->pair_clearance(), states, count, out, path);
  if (proxies.exact_pairs.empty()) return;
  SelfCollisionRequest exact{tolerance};
  exact.only_pairs = &proxies.exact_pairs;
  const std::size_t stride = m_->robot().variable_count();
  for (std::size_t i = 0; i < count; ++i) {
    if (!out[i]) out[i] = check_self(states + i * stride, exact).collision;
  }
}

namespace {
constexpr std::size_t kFieldBatch = 20000;
}  // namespace

// Per link with geometry: moved by some joint (a revolute, continuous, prismatic, floating or
// planar joint on its chain to the root), or fixed. False when no link is fixed.
bool CollisionChecker::split_fixed_links(std::vector<char>& moving, std::vector<char>& fixed) const {
  const RobotModel& robot = m_->robot();
  moving.assign(robot.links().size(), 0);
  fixed.assign(robot.links().size(), 0);
  bool any = false;
  for (std::size_t l = 0; l < robot.links().size(); ++l) {
    if (m_->shapes()[l].empty()) continue;
    bool moves = false;
    for (int j = robot.links()[l].parent_joint; j >= 0 && !moves; j = robot.links()[robot.joints()[j].parent_link].parent_joint) {
      moves = robot.joints()[j].type != JointType::kFixed;
    }
    (moves ? moving : fixed)[l] = 1;
    any = any || !moves;
  }
  return any;
}

std::vector<char> CollisionChecker::check_batch(const double* states, std::size_t count, const Environment* env,
                                                const BatchRequest& request) const {
  if (request.environment && env == nullptr) throw std::invalid_argument("batch check: no environment given");
  if (env != nullptr) require_carried(*env);
  check_limit("a batch with its configurations", double(count), m_->limits().batch_states, "max_batch_states");
  const std::size_t stride = m_->robot().variable_count();
  if (!all_finite(states, count * stride)) {  // the row found, and its message built, only on failure
    for (std::size_t i = 0; i < count; ++i) require_finite_state(states + i * stride, ("batch check: state " + std::to_string(i)).c_str());
  }
  std::vector<char> out(count, 0);
  SelfCollisionRequest self;
  self.tolerance = request.tolerance;
  EnvironmentRequest environment;
  environment.tolerance = request.tolerance;
  environment.root_pose = request.root_pose;
  environment.contacts = false;  // a batch answers yes or no per state
  // The octree's distance field lets most links skip the octree (answers unchanged): a batch
  // uses one already kept for this octree, and builds it when large enough to pay for it (its
  // build against the time it saves a state: docs/performance.md).
  environment.distance_field = count >= kFieldBatch ? EnvironmentRequest::DistanceField::kBuild
                                                    : EnvironmentRequest::DistanceField::kIfKept;
  // Links no joint moves (the root's, and those fixed to it) sit where the root pose puts them in
  // every state: checked once for the batch, and a collision there is every state's.
  std::vector<char> moving, fixed;
  if (request.environment && count > 1 && split_fixed_links(moving, fixed)) {
    EnvironmentRequest once = environment;
    once.only_links = &fixed;
    if (check_environment(states, *env, once).collision) return std::vector<char>(count, 1);
    environment.only_links = &moving;
  }
  // The field looked up once for the batch (a lookup takes a lock).
  const std::shared_ptr<const OctreeDistanceField> field =
      request.environment && !env->octree().empty()
          ? octree_field(*env, request.root_pose, environment.distance_field == EnvironmentRequest::DistanceField::kBuild)
          : nullptr;
  const ProxyLevel* proxies =
      request.self ? a_->proxies_for(proxy_use({request.tolerance, Counterpart::kLink}).decide_up_to) : nullptr;
  // Self checks in the SIMD lanes, four states a step (model/proxy_batch.h); the environment
  // only for the states found free.
  if (proxies != nullptr && proxies->in_lanes()) {
    constexpr std::size_t kBlock = 16;
    ThreadPool::shared().for_each((count + kBlock - 1) / kBlock, 1, [&](std::size_t block) {
      const std::size_t begin = block * kBlock, n = std::min(kBlock, count - begin);
      check_self_in_lanes(*proxies, states + begin * stride, n, request.tolerance, out.data() + begin, request.simd);
      if (!request.environment) return;
      for (std::size_t i = begin; i < begin + n; ++i) {
        if (!out[i]) out[i] = environment_check(states + i * stride, *env, environment, field.get()).collision;
      }
    });
    return out;
  }
  // States are taken in blocks as threads come free: their costs differ by orders of magnitude
  // (a free state near nothing against one deep in clutter). A state that throws (a bad root
  // pose) ends the batch with that error.
  ThreadPool::shared().for_each(count, 16, [&](std::size_t i) {
    const double* q = states + i * stride;
    out[i] = (request.self && check_self(q, self).collision) ||
             (request.environment && environment_check(q, *env, environment, field.get()).collision);
  });
  return out;
}

}  // namespace bvh_collision

namespace bvh_collision {

std::vector<std::size_t> CollisionChecker::pairs_moved_by(const std::vector<int>& variables) const {
  std::vector<char> moving(m_->robot().variable_count(), 0);
  for (const int v : variables) {
    if (v < 0 || static_cast<std::size_t>(v) >= moving.size()) throw std::out_of_range("pairs_moved_by: variable " + std::to_string(v));
    moving[v] = 1;
  }
  const auto& joints = m_->robot().joints();
  auto joint_moves = [&](const RobotJoint& j) {
    if (j.type == JointType::kFixed) return false;
    if (j.mimic >= 0) return joints[j.mimic].variable >= 0 && moving[joints[j.mimic].variable] != 0;
    if (j.variable < 0) return true;  // floating or planar: posed by the request, not a variable
    return moving[j.variable] != 0;
  };
  // Per link, its moving ancestor joints (root to link); a pair's path is what the two do not share.
  std::vector<std::vector<int>> moved_above(m_->robot().links().size());
  for (const int j : m_->robot().joint_order()) {
    const RobotJoint& joint = joints[j];
    moved_above[joint.child_link] = moved_above[joint.parent_link];
    if (joint_moves(joint)) moved_above[joint.child_link].push_back(j);
  }
  std::vector<std::size_t> out;
  for (std::size_t p = 0; p < m_->checked_pairs().size(); ++p) {
    const auto [a, b] = m_->checked_pairs()[p];
    if (moved_above[a] != moved_above[b]) out.push_back(p);
  }
  return out;
}

}  // namespace bvh_collision
