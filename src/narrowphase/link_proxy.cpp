#include "bvh_collision/narrowphase/link_proxy.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <queue>
#include <stdexcept>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "proxy_build_index.h"

namespace bvh_collision {
namespace {

// Levels are built this much tighter than named, so that the margins of the queries (a few
// nanometres, kPoseMargin) stay inside the named bound.
constexpr double kLevelSlack = 1e-5;
// A cube this many halvings below the shape's box is far below any level (2^-40 of a metre box).
constexpr int kMaxDepth = 40;

// The point of the primitive's surface nearest p (p inside the primitive, its frame).
Vec3 nearest_surface_point(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return p.norm() > 0.0 ? Vec3(p * (prim.radius / p.norm())) : Vec3(prim.radius, 0, 0);
    case Primitive::Kind::kBox: {
      int axis = 0;
      (prim.half - p.cwiseAbs()).minCoeff(&axis);
      Vec3 q = p;
      q[axis] = p[axis] < 0.0 ? -prim.half[axis] : prim.half[axis];
      return q;
    }
    case Primitive::Kind::kCylinder: {
      const double rho = p.head<2>().norm();
      if (prim.half_length - std::abs(p.z()) < prim.radius - rho) {
        return Vec3(p.x(), p.y(), p.z() < 0.0 ? -prim.half_length : prim.half_length);
      }
      return rho > 0.0 ? Vec3(p.x() * prim.radius / rho, p.y() * prim.radius / rho, p.z()) : Vec3(prim.radius, 0, p.z());
    }
    case Primitive::Kind::kCapsule: {
      const Vec3 axis(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      const Vec3 off = p - axis;
      return off.norm() > 0.0 ? Vec3(axis + off * (prim.radius / off.norm())) : Vec3(axis + Vec3(prim.radius, 0, 0));
    }
    case Primitive::Kind::kCone: {
      const double h = prim.half_length, slope = prim.radius / std::max(2.0 * h, 1e-300);
      const double rho = p.head<2>().norm(), cos_a = 1.0 / std::sqrt(1.0 + slope * slope);
      const double slant = (slope * (h - p.z()) - rho) * cos_a;
      if (p.z() + h <= slant) return Vec3(p.x(), p.y(), -h);
      // Out along the slant's normal (rho, z) ~ (1, slope) in the half plane through p.
      const Vec3 radial = rho > 0.0 ? Vec3(p.x() / rho, p.y() / rho, 0.0) : Vec3(1.0, 0.0, 0.0);
      return p + slant * cos_a * (radial + Vec3(0.0, 0.0, slope));
    }
  }
  return p;
}

// One shape as the build sees it, in the shape's frame: the distance of a point to the surface
// and whether the point is in the solid.
struct ShapeField {
  const Bvh<Obb>* mesh = nullptr;
  // The exact boundary when it is made of triangles (a closed mesh, a box); empty otherwise.
  std::vector<Triangle> faces;
  Primitive primitive;

  bool solid() const { return mesh == nullptr || mesh->closed(); }
  bool inside(const Vec3& p) const { return mesh ? mesh->closed() && contains_point(*mesh, p) : contains(primitive, p); }
  // The distance to the surface, exact up to rounding when below `limit`, otherwise >= limit;
  // the nearest surface point in `nearest` (when given and the distance is below the limit).
  double surface_distance(const Vec3& p, bool in, double limit, Vec3* nearest) const {
    if (mesh) {
      const DistanceResult r = point_distance(*mesh, Transform::Identity(), p, limit);
      if (nearest) *nearest = r.point_b;
      return std::min(r.distance, limit);
    }
    if (!in) {
      const Vec3 q = closest_point(primitive, p);
      if (nearest) *nearest = q;
      return (p - q).norm();
    }
    const double depth = std::max(0.0, inscribed_depth(primitive, p));
    if (nearest) *nearest = nearest_surface_point(primitive, p);
    return depth;
  }
  // The shape's box (centre, half extents).
  std::pair<Vec3, Vec3> box() const {
    if (!mesh) return {Vec3::Zero(), half_extents(primitive)};
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const Triangle& t : mesh->triangles()) {
      for (int k = 0; k < 3; ++k) lo = lo.cwiseMin(t[k]), hi = hi.cwiseMax(t[k]);
    }
    return {0.5 * (lo + hi), 0.5 * (hi - lo)};
  }
};

// A chosen sphere with the bound it was proven to keep.
struct Chosen {
  Vec3 center;
  double radius;
};

// The cover of one shape (see link_proxy.h): cubes from the shape's box down, largest first. A
// cube that holds no point of the link is dropped; one inside a sphere already chosen is done;
// otherwise the largest proven sphere that contains it is chosen (an interior sphere of radius
// depth + e/2, centred on the inward normal through the surface point nearest the cube), or,
// for a cube small enough, its own ball; else the cube is split.
class ShapeCover {
 public:
  ShapeCover(const ShapeField& field, double half_level) : field_(field), half_level_(half_level), index_(half_level) {}

  void run(const Vec3& center, double half_edge) {
    std::vector<std::pair<Vec3, double>> level{{center, half_edge}}, next;
    for (int depth = 0; !level.empty(); ++depth) {
      if (depth > kMaxDepth) throw std::logic_error("link proxy: no cube small enough for the level");
      next.clear();
      for (const auto& [c, a] : level) {
        if (!cell(c, a)) {
          for (int k = 0; k < 8; ++k) {
            const Vec3 offset((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
            next.emplace_back(c + a * offset, 0.5 * a);
          }
        }
      }
      std::swap(level, next);
    }
  }
  const std::vector<Chosen>& chosen() const { return chosen_; }
  double worst() const { return worst_; }

 private:
  // Settles the cube (true) or asks for it to be split (false).
  bool cell(const Vec3& c, double half_edge) {
    const double h = grown_radius(half_edge * std::sqrt(3.0));
    const bool held = index_.any_near(c, [&](std::uint32_t i) {
      return (chosen_[i].center - c).norm() + h <= chosen_[i].radius * (1.0 - kVolumeMargin);
    });
    if (held) return true;
    const bool in = field_.solid() && field_.inside(c);
    Vec3 nearest;
    const double limit = 4.0 * h + 8.0 * half_level_;
    const double d = field_.surface_distance(c, in, limit, &nearest);
    if (!in && low(d) > h) return true;  // no point of the link in this cube
    if (field_.solid() && d < limit && try_interior(c, h, in, d, nearest)) return true;
    if (high(d) + h <= half_level_) return choose(c, h, high(d) + h);
    if (in && h <= low(d) + half_level_) return choose(c, low(d) + half_level_, half_level_);
    return false;
  }
  // The interior spheres on the normal through the nearest surface point, largest first.
  bool try_interior(const Vec3& c, double h, bool in, double d, const Vec3& nearest) {
    if (!(d > 0.0) && !in) return false;
    Vec3 inward = in ? Vec3(c - nearest) : Vec3(nearest - c);
    if (inward.norm() == 0.0) return false;
    inward.normalize();
    for (double t = 16.0 * (h + half_level_); t >= 0.25 * half_level_; t *= 0.5) {
      const Vec3 center = nearest + t * inward;
      if (!field_.inside(center)) continue;
      const double depth = low(field_.surface_distance(center, true, 2.0 * t + h, nullptr));
      const double radius = depth + half_level_;
      if ((center - c).norm() + h <= radius * (1.0 - kVolumeMargin)) return choose(center, radius, half_level_);
    }
    return false;
  }
  double low(double d) const { return d * (1.0 - kVolumeMargin) - kVolumeMargin; }
  double high(double d) const { return grown_radius(d) + kVolumeMargin; }
  bool choose(const Vec3& c, double radius, double bound) {
    index_.insert(static_cast<std::uint32_t>(chosen_.size()), c, radius);
    chosen_.push_back({c, radius});
    worst_ = std::max(worst_, bound);
    return true;
  }

  const ShapeField& field_;
  double half_level_;
  std::vector<Chosen> chosen_;
  SphereGrid index_;  // chosen_ by position
  double worst_ = 0.0;
};


// ------------------------------------------------------------------ the greedy seed

// Points of the shape's surface about `spacing` apart, each with its inward direction (zero when
// unknown): a barycentric grid on every triangle, or the box's surface grid carried to a
// primitive's surface.
std::vector<std::pair<Vec3, Vec3>> surface_samples(const ShapeField& field, double spacing) {
  std::vector<std::pair<Vec3, Vec3>> out;
  if (!field.faces.empty() || field.mesh) {
    for (const Triangle& t : field.faces.empty() ? field.mesh->triangles() : field.faces) {
      const Vec3 normal = (t[1] - t[0]).cross(t[2] - t[0]);
      const Vec3 inward = normal.norm() > 0.0 ? Vec3(-normal.normalized()) : Vec3::Zero();
      // Along the edges every `spacing`, inside one point per spacing^2 of area (a long sliver
      // gets a line of points, not a grid).
      for (int e = 0; e < 3; ++e) {
        const Vec3 a = t[e], b = t[(e + 1) % 3];
        const int k = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing)));
        for (int i = 0; i < k; ++i) out.emplace_back(a + (b - a) * (double(i) / k), inward);
      }
      const int inner = static_cast<int>(0.5 * normal.norm() / (spacing * spacing));
      for (int i = 0; i < inner; ++i) {  // a low-discrepancy fold of the unit square onto the triangle
        double u = std::fmod(0.5 + i * 0.7548776662466927, 1.0), v = std::fmod(0.5 + i * 0.5698402909980532, 1.0);
        if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
        out.emplace_back(t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]), inward);
      }
    }
    return out;
  }
  const Vec3 half = half_extents(field.primitive) * (1.0 + 1e-6);
  const Eigen::Vector3i n = (2.0 * half / spacing).array().ceil().cast<int>().max(1);
  for (int x = 0; x <= n.x(); ++x) {
    for (int y = 0; y <= n.y(); ++y) {
      for (int z = 0; z <= n.z(); ++z) {
        if (x != 0 && x != n.x() && y != 0 && y != n.y() && z != 0 && z != n.z()) continue;
        const Vec3 p = -half + Vec3(2.0 * half.x() * x / n.x(), 2.0 * half.y() * y / n.y(), 2.0 * half.z() * z / n.z());
        out.emplace_back(closest_point(field.primitive, p), Vec3::Zero());
      }
    }
  }
  return out;
}

// Grid points inside the solid, about `spacing` apart.
std::vector<Vec3> interior_points(const ShapeField& field, double spacing) {
  std::vector<Vec3> out;
  if (!field.solid()) return out;
  const auto [center, half] = field.box();
  const Eigen::Vector3i n = (2.0 * half / spacing).array().ceil().cast<int>().max(1);
  for (int x = 0; x < n.x(); ++x) {
    for (int y = 0; y < n.y(); ++y) {
      for (int z = 0; z < n.z(); ++z) {
        const Vec3 p = center - half + Vec3((x + 0.5) * 2.0 * half.x() / n.x(), (y + 0.5) * 2.0 * half.y() / n.y(),
                                            (z + 0.5) * 2.0 * half.z() / n.z());
        if (field.inside(p)) out.push_back(p);
      }
    }
  }
  return out;
}

class SeedBuilder {
 public:
  SeedBuilder(const ShapeField& field, double half_level) : field_(field), half_level_(half_level) {}

  // A proven interior sphere at p (inside the solid): radius depth + e/2.
  std::optional<Chosen> interior_sphere(const Vec3& p) const {
    if (!field_.inside(p)) return std::nullopt;
    const double depth = field_.surface_distance(p, true, std::numeric_limits<double>::infinity(), nullptr);
    return Chosen{p, depth * (1.0 - kVolumeMargin) - kVolumeMargin + half_level_};
  }
  // The (nearly) largest ball inside the solid that touches the surface at q, grown by e/2.
  std::optional<Chosen> medial_sphere(const Vec3& q, const Vec3& inward, double size) const {
    auto fits = [&](double t) {
      const Vec3 c = q + t * inward;
      const double need = t * (1.0 - 1e-3);  // a bounded query: it stops at the first closer triangle
      return field_.inside(c) && field_.surface_distance(c, true, need, nullptr) >= need;
    };
    double good = 0.0, bad = 0.25 * half_level_;
    while (bad <= size && fits(bad)) good = bad, bad *= 2.0;
    if (good == 0.0) return std::nullopt;
    for (int i = 0; i < 5; ++i) {
      const double mid = 0.5 * (good + bad);
      (fits(mid) ? good : bad) = mid;
    }
    return interior_sphere(q + good * inward);
  }

 private:
  const ShapeField& field_;
  double half_level_;
};

// Greedy set cover of sample points by candidate spheres. Only an efficiency step: ShapeCover
// proves the cover afterwards and fills whatever the samples missed.
std::vector<Chosen> greedy_seed(const ShapeField& field, double half_level, double margin) {
  const double size = field.box().second.maxCoeff();
  const double spacing = std::max(half_level, size / 24.0);
  const SeedBuilder builder(field, half_level);
  std::vector<Vec3> targets;
  std::vector<Chosen> candidates;
  std::size_t sample = 0;
  for (const auto& [q, inward] : surface_samples(field, spacing)) {
    targets.push_back(q);
    // Candidates from every third sample: as good a cover (docs/performance.md), a third of the build.
    if (!field.solid()) {  // a surface only: balls of radius e/2 centred on it
      candidates.push_back({q, half_level * (1.0 - kVolumeMargin) - kVolumeMargin});
      continue;
    }
    if (sample++ % 3 == 0 && inward.squaredNorm() > 0.0) {
      if (auto s = builder.medial_sphere(q, inward, 2.0 * size)) candidates.push_back(*s);
    }
  }
  for (const Vec3& p : interior_points(field, std::max(spacing, size / 12.0))) {
    targets.push_back(p);
    if (auto s = builder.interior_sphere(p)) candidates.push_back(*s);
  }
  // Which targets each candidate covers.
  const PointTree target_tree(targets);
  std::vector<std::vector<int>> covers(candidates.size());
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    target_tree.in_ball(candidates[c].center, std::max(0.0, candidates[c].radius - margin),
                        [&](std::uint32_t t) { covers[c].push_back(static_cast<int>(t)); });
  }
  std::vector<char> covered(targets.size(), 0);
  std::vector<Chosen> chosen;
  std::priority_queue<std::pair<std::size_t, std::size_t>> queue;  // (gain, candidate), lazily updated
  for (std::size_t c = 0; c < candidates.size(); ++c) queue.emplace(covers[c].size(), c);
  while (!queue.empty()) {
    const auto [gain, c] = queue.top();
    queue.pop();
    std::size_t now = 0;
    for (const int t : covers[c]) now += covered[t] == 0;
    if (now == 0) continue;
    if (now < gain) {
      queue.emplace(now, c);
      continue;
    }
    for (const int t : covers[c]) covered[t] = 1;
    chosen.push_back(candidates[c]);
  }
  return chosen;
}


// The cover of a shape whose boundary is triangles (a mesh, a box), proven on its surface and,
// for a solid, in its volume (see link_proxy.h):
//   surface: every triangle lies, with margin delta, inside one chosen sphere (all three corners
//     within radius - delta: the triangle then by convexity), after splitting it in four as often
//     as needed; a piece that no sphere holds gets a sphere of its own. Every point within delta
//     of the surface is then covered. An open mesh is only its surface: done.
//   volume: cubes from the box down; a cube inside one chosen sphere is done, one with no point
//     of the solid is dropped, one whose points all lie within delta of the surface (d + h <
//     delta) is done by the surface step, one deep inside gets the interior sphere at its centre;
//     the others are split.
class PolyhedralCover {
 public:
  PolyhedralCover(const ShapeField& field, double half_level, std::vector<Chosen> seed)
      : field_(field), half_level_(half_level), delta_(0.125 * half_level), builder_(field, half_level), index_(half_level) {
    for (const Chosen& s : seed) add(s);
  }

  void run() {
    for (const Triangle& t : field_.faces) surface(t[0], t[1], t[2], 0);
    if (!field_.solid()) return;  // an open mesh is its surface: nothing inside to cover
    const auto [center, half] = field_.box();
    std::vector<std::pair<Vec3, double>> level{{center, half.maxCoeff() * (1.0 + 1e-9) + 1e-12}}, next;
    for (int depth = 0; !level.empty(); ++depth) {
      if (depth > kMaxDepth) throw std::logic_error("link proxy: no cube small enough for the level");
      next.clear();
      for (const auto& [c, a] : level) {
        if (cube(c, a)) continue;
        for (int k = 0; k < 8; ++k) {
          const Vec3 offset((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
          next.emplace_back(c + a * offset, 0.5 * a);
        }
      }
      std::swap(level, next);
    }
  }
  const std::vector<Chosen>& chosen() const { return chosen_; }

 private:
  bool holds(const Chosen& s, const Vec3& p, double margin) const {
    const double r = (s.radius - margin) * (1.0 - kVolumeMargin) - kVolumeMargin;
    return r > 0.0 && (p - s.center).squaredNorm() <= r * r;
  }
  bool held(const Vec3& a, const Vec3& b, const Vec3& c) {
    if (last_ < chosen_.size() && holds(chosen_[last_], a, delta_) && holds(chosen_[last_], b, delta_) &&
        holds(chosen_[last_], c, delta_)) {
      return true;
    }
    return index_.any_near(a, [&](std::uint32_t i) {
      const bool all = holds(chosen_[i], a, delta_) && holds(chosen_[i], b, delta_) && holds(chosen_[i], c, delta_);
      if (all) last_ = i;
      return all;
    });
  }
  void add(const Chosen& s) {
    index_.insert(static_cast<std::uint32_t>(chosen_.size()), s.center, s.radius);
    chosen_.push_back(s);
  }
  void surface(const Vec3& a, const Vec3& b, const Vec3& c, int depth) {
    if (held(a, b, c)) return;
    const double edge = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (edge > delta_ && depth < kMaxDepth) {
      const Vec3 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
      surface(a, ab, ca, depth + 1), surface(ab, b, bc, depth + 1), surface(ca, bc, c, depth + 1), surface(ab, bc, ca, depth + 1);
      return;
    }
    // A piece no sphere holds: the interior sphere touching it at its centroid, if that holds it,
    // else the ball of radius e/2 around the centroid (a surface point: within e/2 of the link).
    const Vec3 g = (a + b + c) / 3.0;
    const Vec3 normal = (b - a).cross(c - a);
    if (field_.solid() && normal.norm() > 0.0) {
      if (auto s = builder_.medial_sphere(g, -normal.normalized(), 2.0 * field_.box().second.maxCoeff())) {
        if (holds(*s, a, delta_) && holds(*s, b, delta_) && holds(*s, c, delta_)) {
          add(*s);
          return;
        }
      }
    }
    add({g, half_level_ * (1.0 - kVolumeMargin) - kVolumeMargin});
    if (!held(a, b, c)) throw std::logic_error("link proxy: a surface piece larger than the level");
  }
  // Settles the cube (true) or asks for it to be split (false).
  bool cube(const Vec3& c, double half_edge) {
    const double h = grown_radius(half_edge * std::sqrt(3.0));
    if (last_cube_ < chosen_.size() && holds(chosen_[last_cube_], c, h)) return true;
    const bool held_cube = index_.any_near(c, [&](std::uint32_t i) { return holds(chosen_[i], c, h) ? (last_cube_ = i, true) : false; });
    if (held_cube) return true;
    // Whether c is in the solid matters only for a cube the surface does not cross; a mesh's
    // distance does not need it (a ray cast, asked only then).
    const double limit = 4.0 * h + 8.0 * half_level_;
    std::optional<bool> in;
    if (field_.mesh == nullptr) in = field_.inside(c);
    const double d = field_.surface_distance(c, in.value_or(false), limit, nullptr);
    const double d_low = d * (1.0 - kVolumeMargin) - kVolumeMargin, d_high = grown_radius(d) + kVolumeMargin;
    if (d_low > h && !in.has_value()) in = field_.inside(c);
    if (d_low > h && !*in) return true;          // no point of the solid here
    if (d_high + h < delta_) return true;         // every point within delta of the surface
    if (d_low > h && *in && h <= half_level_) {  // deep enough: the interior sphere at c holds it
      add({c, d_low + half_level_});
      return true;
    }
    return false;
  }

  const ShapeField& field_;
  double half_level_, delta_;
  std::vector<Chosen> chosen_;
  SeedBuilder builder_;
  SphereGrid index_;  // chosen_ by position
  std::size_t last_ = 0, last_cube_ = 0;
};

// A sphere that holds leaves [begin, end): from the centre of their box, a few steps of
// Badoiu-Clarkson (move toward the farthest point by 1/(k+2) of the way) tighten it; the radius
// is then the largest reach from the centre found (any centre gives a valid sphere; the steps
// only make it smaller, and a smaller sphere is opened less often in a traversal).
ProxySphere enclosing_sphere(const std::vector<Chosen>& leaves, std::size_t begin, std::size_t end, const Vec3& start) {
  auto reach = [&](const Vec3& c, std::size_t& farthest) {
    double r = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
      const double d = (leaves[i].center - c).norm() + leaves[i].radius;
      if (d > r) r = d, farthest = i;
    }
    return r;
  };
  Vec3 best = start, c = start;
  std::size_t far = begin;
  double best_radius = reach(c, far);
  for (int k = 0; k < 12; ++k) {
    const Vec3 away = leaves[far].center - c;
    const double n = away.norm();
    const Vec3 point = n > 0.0 ? Vec3(leaves[far].center + away * (leaves[far].radius / n)) : leaves[far].center;
    c += (point - c) / (k + 2.0);
    const double r = reach(c, far);
    if (r < best_radius) best_radius = r, best = c;
  }
  return {best, grown_radius(best_radius), 0};
}

// A sphere tree over the chosen spheres (leaves), split top-down at the median of the widest
// axis of their centres; each inner sphere holds its children's.
void build_tree(std::vector<Chosen>& leaves, std::size_t begin, std::size_t end, std::vector<ProxySphere>& out) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = begin; i < end; ++i) {
    lo = lo.cwiseMin(leaves[i].center - Vec3::Constant(leaves[i].radius));
    hi = hi.cwiseMax(leaves[i].center + Vec3::Constant(leaves[i].radius));
  }
  const std::size_t index = out.size();
  if (end - begin == 1) {
    out.push_back({leaves[begin].center, leaves[begin].radius, static_cast<std::int32_t>(index + 1)});
    return;
  }
  out.push_back(enclosing_sphere(leaves, begin, end, 0.5 * (lo + hi)));
  int axis = 0;
  (hi - lo).maxCoeff(&axis);
  const std::size_t mid = begin + (end - begin) / 2;
  std::nth_element(leaves.begin() + begin, leaves.begin() + mid, leaves.begin() + end,
                   [axis](const Chosen& x, const Chosen& y) { return x.center[axis] < y.center[axis]; });
  build_tree(leaves, begin, mid, out);
  build_tree(leaves, mid, end, out);
  out[index].skip = static_cast<std::int32_t>(out.size());
}

}  // namespace

LinkProxy LinkProxy::build(const std::vector<BodyShape>& shapes, double level) {
  if (!(level > 0.0)) throw std::invalid_argument("link proxy: the level must be positive");
  LinkProxy proxy;
  proxy.level_ = level;
  const double half_level = 0.5 * level * (1.0 - kLevelSlack);
  std::vector<Chosen> leaves;
  for (const BodyShape& shape : shapes) {
    ShapeField field;
    field.mesh = shape.shape.mesh;
    field.primitive = shape.shape.primitive;
    if (field.mesh && field.mesh->empty()) continue;
    if (!field.mesh && field.primitive.kind == Primitive::Kind::kSphere) {
      leaves.push_back({shape.origin.t, field.primitive.radius});  // its own exact proxy
      continue;
    }
    if (field.mesh) field.faces = field.mesh->triangles();  // closed: the solid's boundary; open: the link
    if (!field.mesh && field.primitive.kind == Primitive::Kind::kBox) {
      const TriangleMesh box = box_mesh(2.0 * field.primitive.half);
      for (const auto& t : box.triangles) field.faces.push_back({box.vertices[t[0]], box.vertices[t[1]], box.vertices[t[2]]});
    }
    std::vector<Chosen> chosen;
    if (!field.faces.empty()) {
      // The greedy start covers its samples with twice the surface margin, so that the proof
      // rarely needs a sphere of its own.
      PolyhedralCover cover(field, half_level, greedy_seed(field, half_level, 0.25 * half_level));
      cover.run();
      chosen = cover.chosen();
    } else {
      ShapeCover cover(field, half_level);
      const auto [center, half] = field.box();
      cover.run(center, half.maxCoeff() * (1.0 + 1e-9) + 1e-12);
      chosen = cover.chosen();
    }
    proxy.hausdorff_ = std::max(proxy.hausdorff_, half_level);
    for (const Chosen& c : chosen) leaves.push_back({shape.origin * c.center, c.radius});
  }
  proxy.leaves_ = leaves.size();
  if (!leaves.empty()) build_tree(leaves, 0, leaves.size(), proxy.spheres_);
  return proxy;
}

}  // namespace bvh_collision
