#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/detail/filtered_predicates.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_set>

#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision {
namespace {

using Face = std::array<int, 3>;

bool lexicographic_less(const Vec3& a, const Vec3& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

// Four points spanning a volume, found greedily (far apart, then off the line, then off the
// plane), each choice confirmed by an exact predicate. False when the points are coplanar.
bool initial_tetrahedron(const std::vector<Vec3>& p, std::array<int, 4>& t) {
  t = {0, 0, 0, 0};
  double best = -1.0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    if (const double d = (p[i] - p[0]).squaredNorm(); d > best) best = d, t[1] = static_cast<int>(i);
  }
  best = -1.0;
  t[2] = -1;
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double d = (p[i] - p[0]).cross(p[t[1]] - p[0]).squaredNorm();
    if (d > best && projection_axis(p[0], p[t[1]], p[i]) >= 0) best = d, t[2] = static_cast<int>(i);
  }
  if (t[2] < 0) return false;  // collinear
  best = -1.0;
  t[3] = -1;
  const Vec3 normal = (p[t[1]] - p[0]).cross(p[t[2]] - p[0]);
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double d = std::abs(normal.dot(p[i] - p[0]));
    if (d > best && detail::orient3d_filtered(p[0], p[t[1]], p[t[2]], p[i]) != 0) best = d, t[3] = static_cast<int>(i);
  }
  return t[3] >= 0;
}

std::uint64_t edge_key(int u, int v) { return (static_cast<std::uint64_t>(u) << 32) | static_cast<std::uint32_t>(v); }

// Adds point `pi` to the hull `faces` (outward), replacing the faces it sees strictly: exact signs
// make "sees no face" mean "inside or on the hull". Returns false when nothing changed.
bool add_point(const std::vector<Vec3>& p, int pi, std::vector<Face>& faces) {
  thread_local std::vector<char> visible;
  visible.assign(faces.size(), 0);
  bool any = false;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const Face& q = faces[f];
    visible[f] = detail::orient3d_filtered(p[q[0]], p[q[1]], p[q[2]], p[pi]) < 0;
    any = any || visible[f];
  }
  if (!any) return false;
  // The horizon: edges of seen faces whose reverse edge belongs to a face not seen.
  std::unordered_set<std::uint64_t> seen_edges;
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (!visible[f]) continue;
    for (int k = 0; k < 3; ++k) seen_edges.insert(edge_key(faces[f][k], faces[f][(k + 1) % 3]));
  }
  std::vector<Face> next;
  next.reserve(faces.size() + 8);
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (!visible[f]) {
      next.push_back(faces[f]);
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const int u = faces[f][k], v = faces[f][(k + 1) % 3];
      if (!seen_edges.count(edge_key(v, u))) next.push_back({u, v, pi});
    }
  }
  faces.swap(next);
  return true;
}

}  // namespace

ConvexHull convex_hull(const std::vector<Vec3>& points) {
  std::vector<Vec3> p;
  p.reserve(points.size());
  for (const Vec3& x : points) {
    if (x.allFinite()) p.push_back(x);
  }
  std::sort(p.begin(), p.end(), lexicographic_less);
  p.erase(std::unique(p.begin(), p.end()), p.end());
  ConvexHull hull;
  std::array<int, 4> t;
  for (const Vec3& x : p) hull.extent = std::max(hull.extent, x.norm());
  if (p.size() < 4 || !initial_tetrahedron(p, t)) {
    hull.vertices = p;
    return hull;
  }
  std::vector<Face> faces;
  for (int k = 0; k < 4; ++k) {  // each face oriented away from the fourth vertex
    Face f{t[k], t[(k + 1) % 4], t[(k + 2) % 4]};
    if (detail::orient3d_filtered(p[f[0]], p[f[1]], p[f[2]], p[t[(k + 3) % 4]]) < 0) std::swap(f[1], f[2]);
    faces.push_back(f);
  }
  // Far points first: they are the likely vertices, and the hull they make rejects the rest.
  const Vec3 inside = 0.25 * (p[t[0]] + p[t[1]] + p[t[2]] + p[t[3]]);
  std::vector<std::pair<double, int>> order;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (std::find(t.begin(), t.end(), static_cast<int>(i)) == t.end()) {
      order.emplace_back(-(p[i] - inside).squaredNorm(), static_cast<int>(i));
    }
  }
  std::sort(order.begin(), order.end());
  for (const auto& [key, i] : order) add_point(p, i, faces);
  std::vector<int> index(p.size(), -1);
  for (Face& f : faces) {
    for (int& v : f) {
      if (index[v] < 0) {
        index[v] = static_cast<int>(hull.vertices.size());
        hull.vertices.push_back(p[v]);
      }
      v = index[v];
    }
  }
  hull.faces = std::move(faces);
  return hull;
}

}  // namespace bvh_collision
