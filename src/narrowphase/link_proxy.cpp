#include "bvh_collision/narrowphase/link_proxy.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "proxy_build.h"

namespace bvh_collision {
namespace {

using proxy_build::Chosen;

// Levels are built this much tighter than named, so that the margins of the queries (a few
// nanometres, kPoseMargin) stay inside the named bound.
constexpr double kLevelSlack = 1e-5;

// A sphere that holds leaves [begin, end): from the centre of their box, a few steps of
// Badoiu-Clarkson (move toward the farthest point by 1/(k+2) of the way) tighten it; the radius
// is then the largest reach from the centre found (any centre gives a valid sphere; the steps
// only make it smaller, and a smaller sphere is opened less often in a traversal).
ProxySphere enclosing_sphere(const std::vector<Chosen>& leaves, std::size_t begin, std::size_t end, const Vec3& start) {
  auto reach = [&](const Vec3& c, std::size_t& farthest) {
    double r = 0.0;
    for (std::size_t i = begin; i < end; ++i) {
      const double squared = (leaves[i].center - c).squaredNorm();
      // A leaf short of r by far more than the rounding (1e-12 r) cannot be the farthest: its
      // square root, the most of this loop, is not taken (the same r and farthest).
      const double room = r - leaves[i].radius - 1e-12 * r;
      if (room > 0.0 && squared < room * room) continue;
      const double d = std::sqrt(squared) + leaves[i].radius;
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


LinkProxy LinkProxy::build(const std::vector<BodyShape>& shapes, double level, ProxyBuildStats* stats) {
  if (!(level > 0.0)) throw std::invalid_argument("link proxy: the level must be positive");
  ProxyBuildStats work;
  LinkProxy proxy;
  proxy.level_ = level;
  const double half_level = 0.5 * level * (1.0 - kLevelSlack);
  std::vector<Chosen> leaves;
  for (const BodyShape& shape : shapes) {
    proxy_build::ShapeField field;
    field.stats = &work;
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
    // The greedy start covers its samples with twice the surface margin, so that the proof
    // rarely needs a sphere of its own.
    const std::vector<Chosen> chosen = field.faces.empty() ? proxy_build::cover_by_cubes(field, half_level)
                                                           : proxy_build::cover_polyhedron(field, half_level, proxy_build::greedy_seed(field, half_level, 0.25 * half_level));
    proxy.hausdorff_ = std::max(proxy.hausdorff_, half_level);
    for (const Chosen& c : chosen) leaves.push_back({shape.origin * c.center, c.radius});
  }
  proxy.leaves_ = leaves.size();
  if (!leaves.empty()) build_tree(leaves, 0, leaves.size(), proxy.spheres_);
  work.leaves = leaves.size();
  if (stats) {
    stats->cubes += work.cubes, stats->surface_pieces += work.surface_pieces, stats->sphere_tests += work.sphere_tests;
    stats->distance_queries += work.distance_queries, stats->inside_queries += work.inside_queries;
    stats->bvh_volume_tests += work.bvh_volume_tests, stats->candidates += work.candidates, stats->leaves += work.leaves;
    stats->triangle_tests += work.triangle_tests;
  }
  return proxy;
}

}  // namespace bvh_collision
