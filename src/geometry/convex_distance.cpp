// GJK distance between convex sets: vertex sets (convex_hull.h) and primitives, triangles and
// hulls (convex_distance.h).
#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <limits>

#include "bvh_collision/geometry/convex_distance.h"
#include "bvh_collision/geometry/distance.h"
#include "gjk.h"

namespace bvh_collision {
namespace {

using namespace gjk_detail;  // src/geometry/gjk.h

// Where the last distance between two hulls ended, per thread (a small table by the hulls'
// addresses): a pair asked again at a nearby pose (an interval's midpoint after its parent's)
// starts GJK from its last direction and climbs from its last support vertices. The answer comes
// from the closest features GJK ends on, whatever the start (a stale entry, where another hull took a freed one's address, only costs
// steps: hull_support takes any vertex index, or none, as its start).
struct HullPairStart {
  const ConvexHull* a = nullptr;
  const ConvexHull* b = nullptr;
  int vertex_a = -1, vertex_b = -1;
  Vec3 direction = Vec3::Zero();
  int simplex = 0;  // the final simplex's vertex pairs
  int simplex_a[3] = {0, 0, 0}, simplex_b[3] = {0, 0, 0};
};

[[gnu::noinline]] HullPairStart& hull_pair_start(const ConvexHull& a, const ConvexHull& b) {
  thread_local std::array<HullPairStart, 64> table;
  const auto key = reinterpret_cast<std::uintptr_t>(&a) * 31 + reinterpret_cast<std::uintptr_t>(&b);
  return table[(key >> 4) % table.size()];
}


// The features a GJK run ended on, each hull's vertex indices in increasing order: where two runs
// from different starts end on the same closest features, the answers below are the same bits.
struct Features {
  int na = 0, nb = 0;
  int a[3] = {0, 0, 0}, b[3] = {0, 0, 0};
};

Features features_of(const Simplex& s) {
  Features f;
  auto add = [](int* list, int& n, int index) {
    if (std::find(list, list + n, index) == list + n) list[n++] = index;
  };
  auto sort = [](int* list, int n) {  // (three at most)
    for (int i = 1; i < n; ++i) {
      for (int k = i; k > 0 && list[k] < list[k - 1]; --k) std::swap(list[k], list[k - 1]);
    }
  };
  for (int k = 0; k < s.n && k < 3; ++k) add(f.a, f.na, s.ia[k]), add(f.b, f.nb, s.ib[k]);
  sort(f.a, f.na);
  sort(f.b, f.nb);
  return f;
}

// The simplex a cached entry describes, at this pose (empty when an index is no longer a vertex).
Simplex seed_of(const HullPairStart& entry, const ConvexHull& a, const ConvexHull& b, const Transform& b_in_a) {
  Simplex seed;
  for (int k = 0; k < entry.simplex; ++k) {
    const int ia = entry.simplex_a[k], ib = entry.simplex_b[k];
    if (ia < 0 || ib < 0 || static_cast<std::size_t>(ia) >= a.vertices.size() || static_cast<std::size_t>(ib) >= b.vertices.size()) {
      return Simplex{};
    }
    seed.a[k] = a.vertices[ia], seed.b[k] = b_in_a * b.vertices[ib], seed.w[k] = seed.a[k] - seed.b[k];
    seed.ia[k] = ia, seed.ib[k] = ib, seed.weight[k] = 0.0;
    seed.n = k + 1;
  }
  return seed;
}

// The answer from the closest features alone: GJK again on their few vertices from their
// centroids' difference (witnesses, distance), and the certified bound along its direction and its
// triangle's normal from supports of the whole hulls climbed from the features' first vertices
// (a support along those directions is at or next to them). Nothing here depends on how the
// features were found.
void finish_on_features(const ConvexHull& a, const ConvexHull& b, const Transform& b_in_a, const Features& f, double scale,
                        ConvexDistance& out) {
  Vec3 pa[3], pb[3], ca = Vec3::Zero(), cb = Vec3::Zero();
  for (int k = 0; k < f.na; ++k) pa[k] = a.vertices[f.a[k]], ca += pa[k];
  for (int k = 0; k < f.nb; ++k) pb[k] = b_in_a * b.vertices[f.b[k]], cb += pb[k];
  auto best_of = [](const Vec3* p, const int* index, int n, const Vec3& d) {
    int best = 0;
    for (int k = 1; k < n; ++k) best = d.dot(p[k]) > d.dot(p[best]) ? k : best;
    return SupportPoint{p[best], index[best]};
  };
  Vec3 start = ca / f.na - cb / f.nb;
  if (!(start.squaredNorm() > 0.0)) start = pa[0] - pb[0];
  const GjkEnd end = gjk([&](const Vec3& d) { return best_of(pa, f.a, f.na, d); },
                         [&](const Vec3& d) { return best_of(pb, f.b, f.nb, d); }, start, scale,
                         std::numeric_limits<double>::quiet_NaN(), 1e-13 * scale);
  witnesses(end.s, out);
  if (out.vertex_a >= 0) out.on_a = a.vertices[out.vertex_a];
  if (out.vertex_b >= 0) out.on_b = b_in_a * b.vertices[out.vertex_b];
  out.distance = (out.on_a - out.on_b).norm();
  if (end.intersecting || out.distance == 0.0) {
    out.intersecting = true;
    return;
  }
  // The certified bound: the gap between the hulls along a direction, from their support
  // vertices. The witnesses' difference is the natural direction, but at distances far below the
  // shapes' size its rounding tilts it; a triangle's normal comes from long edges and stays
  // accurate (face against face), so the better of the two is kept.
  const Mat3 Rt = b_in_a.R.transpose();
  auto gap_along = [&](const Vec3& n) {
    out.support_queries += 2;
    const double gap = n.dot(a.vertices[hull_support(a, -n, f.a[0])]) - n.dot(b_in_a * b.vertices[hull_support(b, Rt * n, f.b[0])]);
    return gap - 1e-13 * scale - 1e-15 * std::abs(gap);
  };
  const Vec3 along = (out.on_a - out.on_b) / out.distance;
  double bound = gap_along(along);
  if (Vec3 normal; simplex_normal(end.s, along, normal)) bound = std::max(bound, gap_along(normal));
  out.lower_bound = std::max(0.0, bound);
}

}  // namespace

ConvexDistance convex_distance(const ConvexHull& a, const ConvexHull& b, const Transform& b_in_a) {
  ConvexDistance out;
  if (a.empty() || b.empty()) {
    out.lower_bound = out.distance = std::numeric_limits<double>::infinity();
    return out;
  }
  const Mat3 Rt = b_in_a.R.transpose();
  HullPairStart& remembered = hull_pair_start(a, b);
  const bool warm = remembered.a == &a && remembered.b == &b;
  // Each climb starts from the last support vertex (at first, the pair's last answer's).
  int last_a = warm ? remembered.vertex_a : -1, last_b = warm ? remembered.vertex_b : -1;
  auto support_a = [&](const Vec3& d) {
    ++out.support_queries;
    last_a = hull_support(a, d, last_a);
    return SupportPoint{a.vertices[last_a], last_a};
  };
  auto support_b = [&](const Vec3& d) {
    ++out.support_queries;
    last_b = hull_support(b, Rt * d, last_b);
    return SupportPoint{b_in_a * b.vertices[last_b], last_b};
  };
  const double scale = a.extent + b.extent + b_in_a.t.norm();
  // Cold, from the hulls' box centres (their axis extremes'): the first supports then face each
  // other, where two arbitrary vertices' difference can point GJK anywhere.
  auto box_centre = [](const ConvexHull& h) {
    const std::vector<Vec3>& v = h.vertices;
    if (h.faces.empty()) return v[0];
    const std::array<int, 6>& e = h.extremes;
    return Vec3(0.5 * (v[e[0]].x() + v[e[1]].x()), 0.5 * (v[e[2]].y() + v[e[3]].y()), 0.5 * (v[e[4]].z() + v[e[5]].z()));
  };
  Vec3 start = warm ? remembered.direction : box_centre(a) - b_in_a * box_centre(b);
  if (!(start.squaredNorm() > 0.0)) start = a.vertices[0] - b_in_a * b.vertices[0];
  const Simplex seed = warm ? seed_of(remembered, a, b, b_in_a) : Simplex{};
  const GjkEnd end = gjk(support_a, support_b, start, scale, std::numeric_limits<double>::quiet_NaN(), 1e-13 * scale, 0.0,
                         true, &seed);
  remembered = {&a, &b, last_a, last_b, end.last_v};
  if (end.intersecting) {
    witnesses(end.s, out);
    if (out.vertex_a >= 0) out.on_a = a.vertices[out.vertex_a];
    if (out.vertex_b >= 0) out.on_b = b_in_a * b.vertices[out.vertex_b];
    out.distance = (out.on_a - out.on_b).norm();
    out.intersecting = true;
    return out;
  }
  remembered.simplex = std::min(end.s.n, 3);
  for (int k = 0; k < remembered.simplex; ++k) remembered.simplex_a[k] = end.s.ia[k], remembered.simplex_b[k] = end.s.ib[k];
  finish_on_features(a, b, b_in_a, features_of(end.s), scale, out);
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
