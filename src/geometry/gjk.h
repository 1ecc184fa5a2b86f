// GJK on two convex sets given by their support functions (geometry/convex_distance.h's two
// convex_distance overloads share it): the simplex, its reductions to the sub-simplex closest to
// the origin, and the iteration. A header because the iteration is a template over the support
// functions; private to src/geometry.
#pragma once

#include <cmath>
#include <initializer_list>
#include <limits>

#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/types.h"

namespace bvh_collision::gjk_detail {

// A GJK simplex: points w = a - b of the Minkowski difference with where they came from, and the
// barycentric weights of the point of the simplex closest to the origin.
struct Simplex {
  int n = 0;
  Vec3 w[4], a[4], b[4];
  int ia[4], ib[4];
  double weight[4];

  Vec3 point() const {
    Vec3 v = Vec3::Zero();
    for (int k = 0; k < n; ++k) v += weight[k] * w[k];
    return v;
  }
};

// The sub-simplex whose point is closest to the origin, as the vertices it keeps (in increasing
// order) and their weights: computed without touching the simplex, so that the faces of a
// tetrahedron are compared, and the simplex GJK had before a step is kept, with no copy.
struct Reduction {
  int n = 0;
  int keep[4] = {0, 0, 0, 0};
  double weight[4] = {0, 0, 0, 0};

  Reduction() = default;
  Reduction(std::initializer_list<int> which, std::initializer_list<double> weights) {
    auto wt = weights.begin();
    for (const int k : which) keep[n] = k, weight[n++] = *wt++;
  }
  // The same sums in the same order as Simplex::point() of the reduced simplex: the same bits.
  Vec3 point(const Simplex& s) const {
    Vec3 v = Vec3::Zero();
    for (int k = 0; k < n; ++k) v += weight[k] * s.w[keep[k]];
    return v;
  }
};

// `from` reduced to `r`, into `to` (another simplex).
inline void reduce(const Simplex& from, const Reduction& r, Simplex& to) {
  to.n = r.n;
  for (int k = 0; k < r.n; ++k) {
    const int i = r.keep[k];
    to.w[k] = from.w[i], to.a[k] = from.a[i], to.b[k] = from.b[i], to.ia[k] = from.ia[i], to.ib[k] = from.ib[i];
    to.weight[k] = r.weight[k];
  }
}

inline Reduction closest_on_segment(const Simplex& s, int i, int j) {
  const Vec3 d = s.w[j] - s.w[i];
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? -s.w[i].dot(d) / len2 : 0.0;
  if (t <= 0) return {{i}, {1.0}};
  if (t >= 1) return {{j}, {1.0}};
  return {{i, j}, {1 - t, t}};
}

// The Voronoi-region walk of the closest point of triangle (i, j, k) to the origin.
inline Reduction closest_on_triangle(const Simplex& s, int i, int j, int k) {
  const Vec3 &A = s.w[i], &B = s.w[j], &C = s.w[k];
  const Vec3 ab = B - A, ac = C - A;
  const double d1 = -ab.dot(A), d2 = -ac.dot(A);
  if (d1 <= 0 && d2 <= 0) return {{i}, {1.0}};
  const double d3 = -ab.dot(B), d4 = -ac.dot(B);
  if (d3 >= 0 && d4 <= d3) return {{j}, {1.0}};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return {{i, j}, {1 - t, t}};
  }
  const double d5 = -ab.dot(C), d6 = -ac.dot(C);
  if (d6 >= 0 && d5 <= d6) return {{k}, {1.0}};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return {{i, k}, {1 - t, t}};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return {{j, k}, {1 - t, t}};
  }
  const double sum = va + vb + vc;
  if (!(sum > 0)) return closest_on_segment(s, i, j);  // degenerate triangle
  const double v = vb / sum, w = vc / sum;
  return {{i, j, k}, {1 - v - w, v, w}};
}

// Closest point of the tetrahedron to the origin: the best over the faces the origin is outside
// of. Returns false when the origin is inside (the sets intersect).
inline bool closest_on_tetrahedron(const Simplex& s, Reduction& best) {
  static const int kFaces[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
  double best_d = std::numeric_limits<double>::infinity();
  bool outside_any = false;
  for (const auto& f : kFaces) {
    const Vec3 normal = (s.w[f[1]] - s.w[f[0]]).cross(s.w[f[2]] - s.w[f[0]]);
    const double side_origin = -normal.dot(s.w[f[0]]), side_other = normal.dot(s.w[f[3]] - s.w[f[0]]);
    // Outside this face, or the tetrahedron is too flat to tell: try the face.
    if (side_origin * side_other > 0) continue;
    outside_any = true;
    const Reduction t = closest_on_triangle(s, f[0], f[1], f[2]);
    if (const double d = t.point(s).squaredNorm(); d < best_d) best_d = d, best = t;
  }
  return outside_any;
}


// A support point: the point, and its vertex index when the set is a vertex list (-1 otherwise).
struct SupportPoint {
  Vec3 p;
  int index;
};

// What GJK ends with: the simplex, and whether the origin was found inside it.
struct GjkEnd {
  Simplex s;
  bool intersecting = false;
  bool separated = false;  // stopped because the gap along `v` exceeds decide_at
  Vec3 v = Vec3::Zero();   // the last search direction
  Vec3 support_a = Vec3::Zero(), support_b = Vec3::Zero();  // its support points
  // The last direction asked and its support points (whatever stopped GJK): the sets' gap along
  // it is a certified bound with no further support query.
  Vec3 last_v = Vec3::Zero(), last_a = Vec3::Zero(), last_b = Vec3::Zero();
};

// GJK on the Minkowski difference a - b. `support_a(d)` and `support_b(d)` give the farthest
// points along d, both in a's frame. With a finite `decide_at`, stops once |v| <= decide_at (the
// sets are that close) or the gap along v exceeds decide_at + margin (they are farther). With a
// positive `slack`, stops once |v| exceeds the gap along v by at most the slack: the simplex's
// point is then within it of the distance.
// Two simplices take turns: a step appends w to the current one (its first n points stay what
// they were, so dropping w again gives back the simplex before the step) and reduces it into the
// other.
template <class SupportA, class SupportB>
GjkEnd gjk(const SupportA& support_a, const SupportB& support_b, const Vec3& start, double scale, double decide_at,
           double margin, double slack = 0.0, bool decide_near = true, const Simplex* seed = nullptr) {
  GjkEnd end;
  Simplex spare;
  Simplex* s = &end.s;
  Simplex* next_s = &spare;
  Vec3 v = start;
  // A seed (points of the difference: the simplex a nearby pose ended with) starts GJK at its
  // closest point, unless that is (near) the origin: then from `start`, as without one.
  if (seed != nullptr && seed->n > 0 && seed->n < 4) {
    const Reduction r = seed->n == 1 ? Reduction{{0}, {1.0}} : seed->n == 2 ? closest_on_segment(*seed, 0, 1)
                                                                             : closest_on_triangle(*seed, 0, 1, 2);
    if (const Vec3 p = r.point(*seed); p.squaredNorm() > 1e-20 * scale * scale) {
      reduce(*seed, r, *s);
      v = p;
    }
  }
  const bool deciding = std::isfinite(decide_at);
  for (int iteration = 0; iteration < 128; ++iteration) {
    const SupportPoint pa = support_a(-v), pb = support_b(v);
    end.last_v = v, end.last_a = pa.p, end.last_b = pb.p;
    const Vec3 w = pa.p - pb.p;
    const double vv = v.squaredNorm();
    if (deciding && vv > 0.0 && v.dot(w) / std::sqrt(vv) - margin > decide_at) {  // farther: decided
      end.separated = true;
      end.v = v;
      end.support_a = pa.p;
      end.support_b = pb.p;
      break;
    }
    if (s->n > 0 && vv - v.dot(w) <= 1e-15 * vv) break;  // w brings v no closer: converged
    if (slack > 0.0 && s->n > 0 && std::sqrt(vv) - (v.dot(w) / std::sqrt(vv) - margin) <= slack) break;  // close enough
    bool repeated = false;
    for (int k = 0; k < s->n; ++k) {
      // Vertex sets repeat by index; a continuous support point only by value.
      const bool indexed = pa.index >= 0 && pb.index >= 0;
      repeated = repeated || (indexed ? s->ia[k] == pa.index && s->ib[k] == pb.index : s->w[k] == w);
    }
    if (repeated) break;
    const int before = s->n;  // s with its first `before` points: the simplex that gave v
    s->w[before] = w, s->a[before] = pa.p, s->b[before] = pb.p, s->ia[before] = pa.index, s->ib[before] = pb.index;
    s->weight[before] = 0.0;
    s->n = before + 1;
    Reduction r;
    if (s->n == 1) r = {{0}, {1.0}};
    if (s->n == 2) r = closest_on_segment(*s, 0, 1);
    if (s->n == 3) r = closest_on_triangle(*s, 0, 1, 2);
    if (s->n == 4 && !closest_on_tetrahedron(*s, r)) {
      // The origin in the tetrahedron, unless rounding flattened it: a w that is still on the far
      // side of v separates the sets, so that is convergence on a curved surface, not contact.
      if (vv > 0.0 && v.dot(w) > margin * std::sqrt(vv)) {
        s->n = before;
        break;
      }
      end.intersecting = true;  // (with the four points, w's weight 0)
      break;
    }
    const Vec3 next = r.point(*s);
    if (next.squaredNorm() <= 1e-30 * scale * scale) {
      reduce(*s, r, *next_s);
      std::swap(s, next_s);
      end.intersecting = true;
      break;
    }
    if (r.n > 1 && next.squaredNorm() >= vv) {  // no progress: rounding has the last word
      s->n = before;  // the simplex that gave v, so the witnesses are v apart
      break;
    }
    reduce(*s, r, *next_s);
    std::swap(s, next_s);
    v = next;
    if (deciding && decide_near && vv <= decide_at * decide_at) break;  // this close: decided
  }
  if (s != &end.s) end.s = *s;
  return end;
}

// The witnesses of the simplex's closest point, and its distance.
inline void witnesses(const Simplex& s, ConvexDistance& out) {
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
}

// The normal of a triangle simplex, oriented along `along`: accurate where the difference of the
// witnesses is not (face against face, far below the shapes' size).
inline bool simplex_normal(const Simplex& s, const Vec3& along, Vec3& normal) {
  if (s.n != 3) return false;
  normal = (s.w[1] - s.w[0]).cross(s.w[2] - s.w[0]);
  if (!(normal.norm() > 0)) return false;
  if (normal.dot(along) < 0) normal = -normal;
  normal.normalize();
  return true;
}

}  // namespace bvh_collision::gjk_detail
