// GJK distance between two convex vertex sets (see convex_hull.h).
#include <cmath>
#include <limits>

#include "bvh_collision/geometry/convex_hull.h"

namespace bvh_collision {
namespace {

// A GJK simplex: points w = a - b of the Minkowski difference with where they came from, and the
// barycentric weights of the point of the simplex closest to the origin.
struct Simplex {
  int n = 0;
  Vec3 w[4], a[4], b[4];
  int ia[4], ib[4];
  double weight[4];

  void keep(std::initializer_list<int> which, std::initializer_list<double> weights) {
    Simplex s;
    auto wt = weights.begin();
    for (const int k : which) {
      s.w[s.n] = w[k], s.a[s.n] = a[k], s.b[s.n] = b[k], s.ia[s.n] = ia[k], s.ib[s.n] = ib[k];
      s.weight[s.n++] = *wt++;
    }
    *this = s;
  }
  Vec3 point() const {
    Vec3 v = Vec3::Zero();
    for (int k = 0; k < n; ++k) v += weight[k] * w[k];
    return v;
  }
};

void closest_on_segment(Simplex& s, int i, int j) {
  const Vec3 d = s.w[j] - s.w[i];
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? -s.w[i].dot(d) / len2 : 0.0;
  if (t <= 0) return s.keep({i}, {1.0});
  if (t >= 1) return s.keep({j}, {1.0});
  s.keep({i, j}, {1 - t, t});
}

// The Voronoi-region walk of the closest point of triangle (i, j, k) to the origin.
void closest_on_triangle(Simplex& s, int i, int j, int k) {
  const Vec3 &A = s.w[i], &B = s.w[j], &C = s.w[k];
  const Vec3 ab = B - A, ac = C - A;
  const double d1 = -ab.dot(A), d2 = -ac.dot(A);
  if (d1 <= 0 && d2 <= 0) return s.keep({i}, {1.0});
  const double d3 = -ab.dot(B), d4 = -ac.dot(B);
  if (d3 >= 0 && d4 <= d3) return s.keep({j}, {1.0});
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return s.keep({i, j}, {1 - t, t});
  }
  const double d5 = -ab.dot(C), d6 = -ac.dot(C);
  if (d6 >= 0 && d5 <= d6) return s.keep({k}, {1.0});
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return s.keep({i, k}, {1 - t, t});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return s.keep({j, k}, {1 - t, t});
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return closest_on_segment(s, i, j);  // degenerate triangle
  const double v = vb / sum, w = vc / sum;
  s.keep({i, j, k}, {1 - v - w, v, w});
}

// Closest point of the tetrahedron to the origin: the best over the faces the origin is outside
// of. Returns false when the origin is inside (the sets intersect).
bool closest_on_tetrahedron(Simplex& s) {
  static const int kFaces[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
  Simplex best;
  double best_d = std::numeric_limits<double>::infinity();
  bool outside_any = false;
  for (const auto& f : kFaces) {
    const Vec3 normal = (s.w[f[1]] - s.w[f[0]]).cross(s.w[f[2]] - s.w[f[0]]);
    const double side_origin = -normal.dot(s.w[f[0]]), side_other = normal.dot(s.w[f[3]] - s.w[f[0]]);
    // Outside this face, or the tetrahedron is too flat to tell: try the face.
    if (side_origin * side_other > 0) continue;
    outside_any = true;
    Simplex t = s;
    closest_on_triangle(t, f[0], f[1], f[2]);
    if (const double d = t.point().squaredNorm(); d < best_d) best_d = d, best = t;
  }
  if (!outside_any) return false;
  s = best;
  return true;
}

}  // namespace

ConvexDistance convex_distance(const ConvexHull& a, const ConvexHull& b, const Transform& b_in_a) {
  ConvexDistance out;
  if (a.empty() || b.empty()) {
    out.lower_bound = out.distance = std::numeric_limits<double>::infinity();
    return out;
  }
  const Mat3 Rt = b_in_a.R.transpose();
  auto support_a = [&](const Vec3& d) {
    int best = 0;
    double best_dot = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < a.vertices.size(); ++i) {
      if (const double x = d.dot(a.vertices[i]); x > best_dot) best_dot = x, best = static_cast<int>(i);
    }
    return best;
  };
  auto support_b = [&](const Vec3& d) {
    const Vec3 local = Rt * d;
    int best = 0;
    double best_dot = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < b.vertices.size(); ++i) {
      if (const double x = local.dot(b.vertices[i]); x > best_dot) best_dot = x, best = static_cast<int>(i);
    }
    return best;
  };
  auto b_point = [&](int i) -> Vec3 { return b_in_a * b.vertices[i]; };
  const double scale = a.extent + b.extent + b_in_a.t.norm();
  Simplex s;
  Vec3 v = a.vertices[0] - b_point(0);
  for (int iteration = 0; iteration < 128; ++iteration) {
    const int ia = support_a(-v), ib = support_b(v);
    const Vec3 pa = a.vertices[ia], pb = b_point(ib);
    const Vec3 w = pa - pb;
    const double vv = v.squaredNorm();
    if (s.n > 0 && vv - v.dot(w) <= 1e-15 * vv) break;  // w brings v no closer: converged
    bool repeated = false;
    for (int k = 0; k < s.n; ++k) repeated = repeated || (s.ia[k] == ia && s.ib[k] == ib);
    if (repeated) break;
    s.w[s.n] = w, s.a[s.n] = pa, s.b[s.n] = pb, s.ia[s.n] = ia, s.ib[s.n] = ib, s.weight[s.n] = 0.0;
    ++s.n;
    if (s.n == 1) s.keep({0}, {1.0});
    if (s.n == 2) closest_on_segment(s, 0, 1);
    if (s.n == 3) closest_on_triangle(s, 0, 1, 2);
    if (s.n == 4 && !closest_on_tetrahedron(s)) {
      out.intersecting = true;
      break;
    }
    const Vec3 next = s.point();
    if (next.squaredNorm() <= 1e-30 * scale * scale) {
      out.intersecting = true;
      break;
    }
    if (s.n > 1 && next.squaredNorm() >= vv) break;  // no progress: rounding has the last word
    v = next;
  }
  out.on_a = out.on_b = Vec3::Zero();
  for (int k = 0; k < s.n; ++k) {
    out.on_a += s.weight[k] * s.a[k];
    out.on_b += s.weight[k] * s.b[k];
  }
  out.vertex_a = s.ia[0];
  out.vertex_b = s.ib[0];
  for (int k = 1; k < s.n; ++k) {
    if (s.ia[k] != s.ia[0]) out.vertex_a = -1;
    if (s.ib[k] != s.ib[0]) out.vertex_b = -1;
  }
  if (out.vertex_a >= 0) out.on_a = a.vertices[out.vertex_a];
  if (out.vertex_b >= 0) out.on_b = b_point(out.vertex_b);
  out.distance = (out.on_a - out.on_b).norm();
  if (out.intersecting || out.distance == 0.0) {
    out.intersecting = true;
    return out;
  }
  // The certified bound: the gap between the hulls along a direction, from their support
  // vertices. The witnesses' difference is the natural direction, but at distances far below the
  // shapes' size its rounding tilts it; a triangle simplex's normal comes from long edges and
  // stays accurate (face against face), so the better of the two is kept.
  auto gap_along = [&](const Vec3& n) {
    const double gap = n.dot(a.vertices[support_a(-n)]) - n.dot(b_point(support_b(n)));
    return gap - 1e-13 * scale - 1e-15 * std::abs(gap);
  };
  const Vec3 along = (out.on_a - out.on_b) / out.distance;
  double bound = gap_along(along);
  if (s.n == 3) {
    Vec3 normal = (s.w[1] - s.w[0]).cross(s.w[2] - s.w[0]);
    if (normal.dot(along) < 0) normal = -normal;
    if (normal.norm() > 0) bound = std::max(bound, gap_along(normal.normalized()));
  }
  out.lower_bound = std::max(0.0, bound);
  return out;
}

}  // namespace bvh_collision
