// GJK distance between convex sets: vertex sets (convex_hull.h) and primitives, triangles and
// hulls (convex_distance.h).
#include <algorithm>
#include <cmath>
#include <limits>

#include "bvh_collision/geometry/convex_distance.h"
#include "bvh_collision/geometry/distance.h"

namespace bvh_collision {
namespace {

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
void reduce(const Simplex& from, const Reduction& r, Simplex& to) {
  to.n = r.n;
  for (int k = 0; k < r.n; ++k) {
    const int i = r.keep[k];
    to.w[k] = from.w[i], to.a[k] = from.a[i], to.b[k] = from.b[i], to.ia[k] = from.ia[i], to.ib[k] = from.ib[i];
    to.weight[k] = r.weight[k];
  }
}

Reduction closest_on_segment(const Simplex& s, int i, int j) {
  const Vec3 d = s.w[j] - s.w[i];
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? -s.w[i].dot(d) / len2 : 0.0;
  if (t <= 0) return {{i}, {1.0}};
  if (t >= 1) return {{j}, {1.0}};
  return {{i, j}, {1 - t, t}};
}

// The Voronoi-region walk of the closest point of triangle (i, j, k) to the origin.
Reduction closest_on_triangle(const Simplex& s, int i, int j, int k) {
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
bool closest_on_tetrahedron(const Simplex& s, Reduction& best) {
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
           double margin, double slack = 0.0, bool decide_near = true) {
  GjkEnd end;
  Simplex spare;
  Simplex* s = &end.s;
  Simplex* next_s = &spare;
  Vec3 v = start;
  const bool deciding = std::isfinite(decide_at);
  for (int iteration = 0; iteration < 128; ++iteration) {
    const SupportPoint pa = support_a(-v), pb = support_b(v);
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
void witnesses(const Simplex& s, ConvexDistance& out) {
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
bool simplex_normal(const Simplex& s, const Vec3& along, Vec3& normal) {
  if (s.n != 3) return false;
  normal = (s.w[1] - s.w[0]).cross(s.w[2] - s.w[0]);
  if (!(normal.norm() > 0)) return false;
  if (normal.dot(along) < 0) normal = -normal;
  normal.normalize();
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
  auto b_point = [&](int i) -> Vec3 { return b_in_a * b.vertices[i]; };
  int last_a = -1, last_b = -1;  // each climb starts from the last support vertex
  auto support_a = [&](const Vec3& d) {
    last_a = hull_support(a, d, last_a);
    return SupportPoint{a.vertices[last_a], last_a};
  };
  auto support_b = [&](const Vec3& d) {
    last_b = hull_support(b, Rt * d, last_b);
    return SupportPoint{b_point(last_b), last_b};
  };
  const double scale = a.extent + b.extent + b_in_a.t.norm();
  const GjkEnd end = gjk(support_a, support_b, a.vertices[0] - b_point(0), scale,
                         std::numeric_limits<double>::quiet_NaN(), 1e-13 * scale);
  const Simplex& s = end.s;
  witnesses(s, out);
  if (out.vertex_a >= 0) out.on_a = a.vertices[out.vertex_a];
  if (out.vertex_b >= 0) out.on_b = b_point(out.vertex_b);
  out.distance = (out.on_a - out.on_b).norm();
  if (end.intersecting || out.distance == 0.0) {
    out.intersecting = true;
    return out;
  }
  // The certified bound: the gap between the hulls along a direction, from their support
  // vertices. The witnesses' difference is the natural direction, but at distances far below the
  // shapes' size its rounding tilts it; a triangle simplex's normal comes from long edges and
  // stays accurate (face against face), so the better of the two is kept.
  auto gap_along = [&](const Vec3& n) {
    const double gap = n.dot(support_a(-n).p) - n.dot(support_b(n).p);
    return gap - 1e-13 * scale - 1e-15 * std::abs(gap);
  };
  const Vec3 along = (out.on_a - out.on_b) / out.distance;
  double bound = gap_along(along);
  if (Vec3 normal; simplex_normal(s, along, normal)) bound = std::max(bound, gap_along(normal));
  out.lower_bound = std::max(0.0, bound);
  return out;
}

namespace {

// The set's support point in its own frame.
SupportPoint own_support(const ConvexShape& s, const Vec3& d, int from = -1) {
  switch (s.kind) {
    case ConvexShape::Kind::kPrimitive: return {support(s.primitive, d), -1};
    case ConvexShape::Kind::kTriangle: {
      int best = 0;
      double best_dot = d.dot(s.triangle[0]);
      for (int k = 1; k < 3; ++k) {
        if (const double x = d.dot(s.triangle[k]); x > best_dot) best_dot = x, best = k;
      }
      return {s.triangle[best], best};
    }
    case ConvexShape::Kind::kHull: {
      const int best = hull_support(*s.hull, d, from);
      return {s.hull->vertices[best], best};
    }
  }
  return {Vec3::Zero(), -1};
}

// The point of the set closest to p (own frame); false for a hull (GJK is exact on polytopes).
bool own_closest(const ConvexShape& s, const Vec3& p, Vec3& out) {
  if (s.kind == ConvexShape::Kind::kPrimitive) {
    out = closest_point(s.primitive, p);
    return true;
  }
  if (s.kind == ConvexShape::Kind::kTriangle) {
    out = closest_point_on_triangle(p, s.triangle[0], s.triangle[1], s.triangle[2]);
    return true;
  }
  return false;
}

// Alternating projections from GJK's witnesses: each step takes the closest point of one set to
// the other's witness, so the witnesses' distance only falls, and it falls fast where GJK's
// simplex creeps along a curved surface. Both witnesses stay points of their sets.
// Stops when a step gains less than `enough` or after 64 steps (the gain shrinks geometrically).
void polish_witnesses(const ConvexShape& a, const ConvexShape& b, const Transform& b_in_a, double enough,
                      ConvexDistance& out) {
  for (int step = 0; step < 64; ++step) {
    Vec3 qa, qb_local;
    if (!own_closest(a, out.on_b, qa) || !own_closest(b, b_in_a.R.transpose() * (qa - b_in_a.t), qb_local)) return;
    const Vec3 qb = b_in_a * qb_local;
    const double apart = (qa - qb).norm();
    if (!(apart < out.distance)) return;
    const double gain = out.distance - apart;
    out.on_a = qa, out.on_b = qb, out.distance = apart;
    out.vertex_a = out.vertex_b = -1;
    if (gain <= enough) return;
  }
}

bool curved(const ConvexShape& s) {
  return s.kind == ConvexShape::Kind::kPrimitive && s.primitive.kind != Primitive::Kind::kBox;
}

// Directions where a set's faces make the gap function kink: flat faces (a triangle's normal, a
// box's or a cylinder's axes, a cone's base), in a's frame. The gap along them is exact where rounding tilts
// GJK's direction most (face against face).
int face_directions(const ConvexShape& s, const Mat3& R, Vec3* out) {
  if (s.kind == ConvexShape::Kind::kTriangle) {
    const Vec3 n = (s.triangle[1] - s.triangle[0]).cross(s.triangle[2] - s.triangle[0]);
    if (!(n.norm() > 0)) return 0;
    out[0] = R * n.normalized();
    return 1;
  }
  if (s.kind != ConvexShape::Kind::kPrimitive) return 0;
  if (s.primitive.kind == Primitive::Kind::kBox) {
    for (int i = 0; i < 3; ++i) out[i] = R.col(i);
    return 3;
  }
  if (s.primitive.kind == Primitive::Kind::kCylinder || s.primitive.kind == Primitive::Kind::kCone) {
    out[0] = R.col(2);  // the caps' (the base's) normal
    return 1;
  }
  return 0;
}

// Unit vectors perpendicular to n and to each other.
void perpendicular_basis(const Vec3& n, Vec3& e1, Vec3& e2) {
  const Vec3 helper = std::abs(n.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  e1 = n.cross(helper).normalized();
  e2 = n.cross(e1);
}

// Maximises gap(n) over unit n near `n` by a pattern search whose step halves when no neighbour
// improves: the gap is smooth or a cone near its maximum, and its evaluation does not cancel,
// so the search reaches directions far more accurate than GJK's simplex gives.
// Stops once the bound exceeds `enough`.
template <class Gap>
double refine_direction(const Gap& gap, Vec3& n, double bound, double step, double enough) {
  Vec3 e1, e2;
  perpendicular_basis(n, e1, e2);
  for (int evaluations = 0; step > 1e-13 && evaluations < 400;) {
    if (bound > enough) break;
    bool moved = false;
    for (const Vec3& dir : {Vec3(e1), Vec3(-e1), Vec3(e2), Vec3(-e2)}) {
      const Vec3 m = (n + step * dir).normalized();
      const double g = gap(m);
      ++evaluations;
      if (g > bound) {
        bound = g, n = m, moved = true;
        perpendicular_basis(n, e1, e2);
        break;
      }
    }
    if (!moved) step *= 0.5;
  }
  return bound;
}

}  // namespace

double extent(const ConvexShape& s) {
  switch (s.kind) {
    case ConvexShape::Kind::kPrimitive: return bounding_radius(s.primitive);
    case ConvexShape::Kind::kTriangle:
      return std::max({s.triangle[0].norm(), s.triangle[1].norm(), s.triangle[2].norm()});
    case ConvexShape::Kind::kHull: return s.hull->extent;
  }
  return 0.0;
}

ConvexDistance convex_distance(const ConvexShape& a, const ConvexShape& b, const Transform& b_in_a, double decide_at,
                               double slack, bool far_only) {
  ConvexDistance out;
  auto empty = [](const ConvexShape& s) { return s.kind == ConvexShape::Kind::kHull && s.hull->empty(); };
  if (empty(a) || empty(b)) {
    out.lower_bound = out.distance = std::numeric_limits<double>::infinity();
    return out;
  }
  const Mat3 Rt = b_in_a.R.transpose();
  // (Each hull's climb starts from its last support vertex: GJK's directions turn a little a step.)
  int last_a = -1, last_b = -1;
  auto support_a = [&](const Vec3& d) {
    ++out.support_queries;
    const SupportPoint p = own_support(a, d, last_a);
    last_a = p.index;
    return p;
  };
  auto support_b = [&](const Vec3& d) {
    ++out.support_queries;
    const SupportPoint p = own_support(b, Rt * d, last_b);
    last_b = p.index;
    return SupportPoint{b_in_a * p.p, p.index};
  };
  const double scale = extent(a) + extent(b) + b_in_a.t.norm();
  // Rounding of support values: a few ulps of the scale per term (see the header).
  const double margin = 1e-14 * scale;
  auto gap_along = [&](const Vec3& n) {
    const double gap = n.dot(support_a(-n).p) - n.dot(support_b(n).p);
    return gap - margin - 1e-15 * std::abs(gap);
  };
  const Vec3 start = b_in_a.t.norm() > 0 ? Vec3(-b_in_a.t) : Vec3(Vec3::UnitX());
  slack = std::isfinite(slack) ? std::max(slack, 0.0) : 0.0;
  const GjkEnd end = gjk(support_a, support_b, start, scale, decide_at, margin, slack, !far_only);
  if (end.separated) {
    // Farther than asked along v: the gap along v is the certified answer; the support points
    // are a pair of points of the sets, so their distance bounds the true one from above.
    const Vec3 n = end.v.normalized();
    out.lower_bound = std::max(0.0, gap_along(n));
    if (end.s.n > 0) {
      witnesses(end.s, out);
    } else {
      out.on_a = end.support_a, out.on_b = end.support_b;
    }
    out.distance = std::max((out.on_a - out.on_b).norm(), out.lower_bound);
    return out;
  }
  witnesses(end.s, out);
  out.distance = (out.on_a - out.on_b).norm();
  if (end.intersecting || out.distance == 0.0) {
    out.intersecting = true;
    out.distance = 0.0;
    out.on_b = out.on_a;  // one witness for both: (near) a point the sets share
    return out;
  }
  const Vec3 along = (out.on_a - out.on_b) / out.distance;
  Vec3 best_n = along;
  double bound = gap_along(along);
  auto consider = [&](Vec3 n) {
    if (n.dot(along) < 0) n = -n;
    if (const double g = gap_along(n); g > bound) bound = g, best_n = n;
  };
  if (Vec3 normal; simplex_normal(end.s, along, normal)) consider(normal);
  Vec3 faces[3];
  for (int k = 0, n = face_directions(a, Mat3::Identity(), faces); k < n; ++k) consider(faces[k]);
  for (int k = 0, n = face_directions(b, b_in_a.R, faces); k < n; ++k) consider(faces[k]);
  const bool decided = (std::isfinite(decide_at) && (bound > decide_at || (!far_only && out.distance <= decide_at))) ||
                       out.distance - bound <= slack;
  const double loose = out.distance - bound;
  if (!decided && (curved(a) || curved(b)) && loose > 1e-13 * scale + 1e-9 * out.distance) {
    // The direction error behind the loss: about sqrt(loss / curvature radius) for a curved face.
    const double step = std::clamp(std::sqrt(loose / std::max(scale, 1e-300)), 1e-10, 0.1);
    const double tight = out.distance - std::max(1e-13 * scale + 1e-9 * out.distance, slack);
    // (Far only: above decide_at, or within the slack, whichever comes first.)
    const double enough = !std::isfinite(decide_at) ? tight : far_only ? std::min(decide_at, tight) : decide_at;
    bound = refine_direction(gap_along, best_n, bound, step, enough);
  }
  if ((curved(a) || curved(b)) && out.distance - bound > std::max(1e-15 * scale, slack)) {
    polish_witnesses(a, b, b_in_a, 1e-15 * scale, out);
  }
  out.lower_bound = std::max(0.0, bound);
  // Points of the sets never get closer than the certified bound; a witness distance below it is
  // rounding in the subtraction.
  out.distance = std::max(out.distance, out.lower_bound);
  return out;
}

}  // namespace bvh_collision
