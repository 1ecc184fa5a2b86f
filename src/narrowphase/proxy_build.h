// The pieces of LinkProxy::build (narrowphase/link_proxy.h, where the construction and its proof
// are described), private to the narrowphase: a shape as the build sees it, the greedy start
// (proxy_seed.cpp) and the two proven covers (proxy_cover.cpp). The build's searches live in
// proxy_build_index.h.
#pragma once

#include <limits>
#include <optional>
#include <utility>
#include <vector>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/narrowphase/link_proxy.h"

namespace bvh_collision {
namespace proxy_build {

// A cube this many halvings below the shape's box is far below any level (2^-40 of a metre box).
constexpr int kMaxDepth = 40;

// The point of the primitive's surface nearest p (p inside the primitive, its frame).
Vec3 nearest_surface_point(const Primitive& prim, const Vec3& p);

// One shape as the build sees it, in the shape's frame: the distance of a point to the surface
// and whether the point is in the solid.
struct ShapeField {
  const Bvh<Obb>* mesh = nullptr;
  // The exact boundary when it is made of triangles (a closed mesh, a box); empty otherwise.
  std::vector<Triangle> faces;
  Primitive primitive;
  ProxyBuildStats* stats = nullptr;  // never null during a build

  bool solid() const { return mesh == nullptr || mesh->closed(); }
  bool inside(const Vec3& p) const {
    ++stats->inside_queries;
    if (!mesh) return contains(primitive, p);
    QueryStats q;
    const bool in = mesh->closed() && contains_point(*mesh, p, &q);
    stats->bvh_volume_tests += q.volume_tests;
    return in;
  }
  // The winding number of a closed mesh's surface around p (nothing for a primitive, an open
  // mesh, a point on the surface): inside() is whether it is not 0.
  std::optional<int> winding(const Vec3& p) const {
    if (!mesh) return std::nullopt;
    ++stats->inside_queries;
    QueryStats q;
    const std::optional<int> w = winding_number(*mesh, p, &q);
    stats->bvh_volume_tests += q.volume_tests;
    return w;
  }
  // Is the surface closer than `radius` to p? surface_distance(p, in, radius, nullptr) < radius,
  // answered by a walk that stops at the first closer triangle.
  bool within(const Vec3& p, bool in, double radius) const {
    if (!mesh) return surface_distance(p, in, radius, nullptr) < radius;
    ++stats->distance_queries;
    QueryStats q;
    const bool near = point_within(*mesh, Transform::Identity(), p, radius, &q);
    stats->bvh_volume_tests += q.volume_tests;
    return near;
  }
  // The distance to the surface, exact up to rounding when below `limit`, otherwise >= limit;
  // the nearest surface point in `nearest` (when given and the distance is below the limit).
  double surface_distance(const Vec3& p, bool in, double limit, Vec3* nearest) const {
    ++stats->distance_queries;
    if (mesh) {
      const DistanceResult r = point_distance(*mesh, Transform::Identity(), p, limit);
      stats->bvh_volume_tests += r.stats.volume_tests;
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

class SeedBuilder {
 public:
  SeedBuilder(const ShapeField& field, double half_level) : field_(field), half_level_(half_level) {}

  // The proven interior sphere at p, a point of the solid `depth` from its surface: radius
  // depth + e/2.
  Chosen interior_sphere(const Vec3& p, double depth) const {
    return Chosen{p, depth * (1.0 - kVolumeMargin) - kVolumeMargin + half_level_};  // as sphere_inside
  }
  // The (nearly) largest ball inside the solid that touches the surface at q, grown by e/2.
  // Whether a centre is in the solid is asked once: a ball free of the surface that overlaps one
  // shown inside is inside too (their union is connected and crosses no surface), and every ball
  // tried after the first good one overlaps it (|t - t'| < t + t').
  std::optional<Chosen> medial_sphere(const Vec3& q, const Vec3& inward, double size) const {
    bool in = false;
    auto fits = [&](double t) {
      const Vec3 c = q + t * inward;
      if (field_.within(c, true, t * (1.0 - 1e-3))) return false;
      return in || (in = field_.inside(c));
    };
    double good = 0.0, bad = 0.25 * half_level_;
    while (bad <= size && fits(bad)) good = bad, bad *= 2.0;
    if (good == 0.0) return std::nullopt;
    for (int i = 0; i < 5; ++i) {
      const double mid = 0.5 * (good + bad);
      (fits(mid) ? good : bad) = mid;
    }
    // Its depth is at most good (q is on the surface, within rounding: 1e-16 of the sizes, far
    // below the room left above good): a search bounded there finds it, and sooner than at 2 good.
    return sphere_inside(q + good * inward, good * (1.0 + 1e-9) + 1e-12);
  }

 private:
  // The interior sphere at p, known to be in the solid and closer than `limit` to its surface.
  Chosen sphere_inside(const Vec3& p, double limit) const {
    const double depth = field_.surface_distance(p, true, limit, nullptr);
    return Chosen{p, depth * (1.0 - kVolumeMargin) - kVolumeMargin + half_level_};
  }

  const ShapeField& field_;
  double half_level_;
};

// Spheres chosen by a greedy set cover of points sampled on and in the shape (an efficiency
// step only: the covers below prove what they keep); `margin` is how far inside a sphere a
// sample must lie to count as covered.
std::vector<Chosen> greedy_seed(const ShapeField& field, double half_level, double margin);

// The proven cover of a shape whose boundary is triangles (a mesh, a box), from a seed.
std::vector<Chosen> cover_polyhedron(const ShapeField& field, double half_level, std::vector<Chosen> seed);

// The proven cover of a primitive with curved faces (cylinder, capsule, cone), by cubes.
std::vector<Chosen> cover_by_cubes(const ShapeField& field, double half_level);

}  // namespace proxy_build
}  // namespace bvh_collision
