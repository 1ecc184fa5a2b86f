#include "bvh_collision/checker/collision_checker.h"

#include "bvh_collision/geometry/thread_pool.h"

#include <algorithm>
#include <map>
#include <optional>
#include <stdexcept>

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

// A sphere in the link frame that holds every shape of the link.
template <class ShapeList, class MeshList>
std::pair<Vec3, double> bounding_sphere(const ShapeList& shapes, const MeshList& meshes) {
  Aabb box;
  for (const auto& s : shapes) {
    if (s.mesh < 0) {
      const double r = bounding_radius(s.primitive);
      box.extend(s.origin.t - Vec3::Constant(r));
      box.extend(s.origin.t + Vec3::Constant(r));
      continue;
    }
    for (const Triangle& t : meshes[s.mesh].triangles()) {
      for (int k = 0; k < 3; ++k) box.extend(s.origin * t[k]);
    }
  }
  const Vec3 c = center(box);
  double r = 0.0;
  for (const auto& s : shapes) {
    if (s.mesh < 0) {
      r = std::max(r, (s.origin.t - c).norm() + bounding_radius(s.primitive));
      continue;
    }
    for (const Triangle& t : meshes[s.mesh].triangles()) {
      for (int k = 0; k < 3; ++k) r = std::max(r, (s.origin * t[k] - c).norm());
    }
  }
  return {c, r * (1 + 1e-12) + 1e-12};
}

thread_local std::vector<Transform> tl_poses;

}  // namespace

CollisionChecker::CollisionChecker(RobotModel model, AllowedCollisionMatrix acm, const CheckerOptions& options)
    : model_(std::move(model)), acm_(std::move(acm)) {
  const std::size_t n = model_.links().size();
  if (acm_.size() != n) acm_ = AllowedCollisionMatrix(n);
  padding_.resize(n, options.padding);
  for (std::size_t l = 0; l < n; ++l) {
    if (const auto it = options.link_padding.find(model_.links()[l].name); it != options.link_padding.end()) {
      padding_[l] = it->second;
    }
  }
  // The pairs to check. Every link with geometry gets its BVH: environment queries check links
  // that no self pair needs.
  std::vector<bool> needed(n, false);
  for (std::size_t a = 0; a < n; ++a) {
    needed[a] = !model_.links()[a].collision.empty();
    for (std::size_t b = a + 1; b < n; ++b) {
      if (model_.links()[a].collision.empty() || model_.links()[b].collision.empty() || acm_.allowed(a, b)) continue;
      checked_pairs_.emplace_back(static_cast<int>(a), static_cast<int>(b));
    }
  }
  shapes_.resize(n);
  bounds_.resize(n);
  std::map<const TriangleMesh*, int> built;
  for (std::size_t l = 0; l < n; ++l) {
    if (!needed[l]) continue;
    for (const CollisionElement& e : model_.links()[l].collision) {
      Shape s;
      s.origin = e.origin;
      if (e.shape == CollisionElement::Shape::kSphere) {
        s.primitive = Primitive::sphere(e.radius);
      } else if (e.shape == CollisionElement::Shape::kCylinder) {
        s.primitive = Primitive::cylinder(e.radius, e.length);
      } else {
        auto [it, fresh] = built.emplace(e.mesh.get(), static_cast<int>(meshes_.size()));
        if (fresh) {
          meshes_.push_back(Bvh<Obb>::build(*e.mesh, options.bvh));
          // Surface vertices only: a hull vertex is taken to lie on the mesh (meshes_distance).
          hulls_.push_back(convex_hull(used_vertices(*e.mesh)));
        }
        s.mesh = it->second;
      }
      shapes_[l].push_back(s);
    }
    const auto [c, r] = bounding_sphere(shapes_[l], meshes_);
    bounds_[l] = {c, r};
  }
  kinematics_ = KinematicsPlan(model_, needed);
  compute_motion_rates();
}

bool CollisionChecker::pair_collides(int a, int b, const std::vector<Transform>& poses,
                                     const SelfCollisionRequest& request, SelfCollisionResult& result) const {
  detail::PairRequest pair;
  pair.padding = padding_[a] + padding_[b];
  pair.tolerance = request.tolerance;
  pair.max_contacts = request.max_contacts;
  pair.solids = request.solids;
  bool hit = false;
  std::vector<MeshContact> contacts;
  for (const Shape& sa : shapes_[a]) {
    for (const Shape& sb : shapes_[b]) {
      const bool want_contacts = request.max_contacts > 0 && contacts.size() < request.max_contacts;
      if (detail::shapes_collide(ref(sa), poses[a] * sa.origin, ref(sb), poses[b] * sb.origin, pair,
                                 want_contacts ? &contacts : nullptr, result.stats)) {
        hit = true;
        if (request.max_contacts == 0) return true;
      }
    }
  }
  contacts.resize(std::min(contacts.size(), request.max_contacts));
  for (const MeshContact& c : contacts) result.contacts.push_back({a, b, c});
  return hit;
}

double CollisionChecker::pair_distance(int a, int b, const std::vector<Transform>& poses, double best,
                                       const SelfCollisionRequest& request, SelfCollisionResult& result) const {
  for (const Shape& sa : shapes_[a]) {
    for (const Shape& sb : shapes_[b]) {
      Vec3 wa, wb;
      const double d =
          detail::shapes_distance(ref(sa), poses[a] * sa.origin, ref(sb), poses[b] * sb.origin, best, request.solids, wa, wb,
                          result.stats, request.tolerance);
      if (d < best) {
        best = d;
        result.min_distance = d;
        result.closest_a = a;
        result.closest_b = b;
        result.point_a = wa;
        result.point_b = wb;
      }
    }
  }
  return best;
}

SelfCollisionResult CollisionChecker::check_self(const double* state, const SelfCollisionRequest& request) const {
  SelfCollisionResult result;
  std::vector<Transform>& poses = tl_poses;
  kinematics_.compute(state, poses);
  // Broad phase: the gap between the links' bounding spheres, a lower bound on their distance.
  thread_local std::vector<Vec3> centers;
  centers.resize(poses.size());
  for (std::size_t l = 0; l < poses.size(); ++l) {
    if (bounds_[l].radius >= 0) centers[l] = poses[l].R * bounds_[l].center + poses[l].t;
  }
  thread_local std::vector<std::pair<double, std::size_t>> order;
  order.clear();
  if (!request.distance) {
    // Collision only: the pairs whose spheres come within reach, deepest overlap (relative to
    // the reach) first, because those collide most often and a boolean query stops at the first.
    for (const std::size_t p : PairIndices(request.only_pairs, checked_pairs_.size())) {
      const auto [a, b] = checked_pairs_[p];
      const double reach = bounds_[a].radius + bounds_[b].radius + padding_[a] + padding_[b] + request.tolerance;
      const double d2 = (centers[a] - centers[b]).squaredNorm();
      if (d2 <= reach * reach) order.emplace_back(d2 / (reach * reach), p);
    }
    if (!request.all_pairs) std::sort(order.begin(), order.end());
    for (const auto& [key, p] : order) {
      const auto [a, b] = checked_pairs_[p];
      if (pair_collides(a, b, poses, request, result)) {
        result.collision = true;
        result.colliding_pairs.emplace_back(a, b);
        if (!request.all_pairs) break;
      }
    }
    return result;
  }
  // Distance: nearest pairs first, so that a small bound prunes the rest early.
  for (const std::size_t p : PairIndices(request.only_pairs, checked_pairs_.size())) {
    const auto [a, b] = checked_pairs_[p];
    order.emplace_back((centers[a] - centers[b]).norm() - bounds_[a].radius - bounds_[b].radius, p);
  }
  std::sort(order.begin(), order.end());
  double best = std::numeric_limits<double>::infinity();
  for (const auto& [gap, p] : order) {
    const auto [a, b] = checked_pairs_[p];
    const bool may_collide = gap <= padding_[a] + padding_[b] + request.tolerance;
    if (may_collide && (request.all_pairs || !result.collision) && pair_collides(a, b, poses, request, result)) {
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

std::vector<char> CollisionChecker::check_batch(const double* states, std::size_t count, const Environment* env,
                                                const BatchRequest& request) const {
  if (request.environment && env == nullptr) throw std::invalid_argument("batch check: no environment given");
  std::vector<char> out(count, 0);
  SelfCollisionRequest self;
  self.tolerance = request.tolerance;
  EnvironmentRequest environment;
  environment.tolerance = request.tolerance;
  environment.root_pose = request.root_pose;
  const std::size_t stride = model_.variable_count();
  // States are taken in blocks as threads come free: their costs differ by orders of magnitude
  // (a free state near nothing against one deep in clutter). A state that throws (a bad root
  // pose) ends the batch with that error.
  ThreadPool::shared().for_each(count, 16, [&](std::size_t i) {
    const double* q = states + i * stride;
    out[i] = (request.self && check_self(q, self).collision) ||
             (request.environment && check_environment(q, *env, environment).collision);
  });
  return out;
}

}  // namespace bvh_collision

namespace bvh_collision {

std::vector<std::size_t> CollisionChecker::pairs_moved_by(const std::vector<int>& variables) const {
  std::vector<char> moving(model_.variable_count(), 0);
  for (const int v : variables) {
    if (v < 0 || static_cast<std::size_t>(v) >= moving.size()) throw std::out_of_range("pairs_moved_by: variable " + std::to_string(v));
    moving[v] = 1;
  }
  const auto& joints = model_.joints();
  auto joint_moves = [&](const RobotJoint& j) {
    if (j.type == JointType::kFixed) return false;
    if (j.mimic >= 0) return joints[j.mimic].variable >= 0 && moving[joints[j.mimic].variable] != 0;
    if (j.variable < 0) return true;  // floating or planar: posed by the request, not a variable
    return moving[j.variable] != 0;
  };
  // Per link, its moving ancestor joints (root to link); a pair's path is what the two do not share.
  std::vector<std::vector<int>> moved_above(model_.links().size());
  for (const int j : model_.joint_order()) {
    const RobotJoint& joint = joints[j];
    moved_above[joint.child_link] = moved_above[joint.parent_link];
    if (joint_moves(joint)) moved_above[joint.child_link].push_back(j);
  }
  std::vector<std::size_t> out;
  for (std::size_t p = 0; p < checked_pairs_.size(); ++p) {
    const auto [a, b] = checked_pairs_[p];
    if (moved_above[a] != moved_above[b]) out.push_back(p);
  }
  return out;
}

}  // namespace bvh_collision
