// CGAL as the independent oracle for the geometry layer (test-only dependency).
#pragma once

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision::test {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;

template <class K>
typename K::Point_3 to_cgal(const Vec3& p) {
  return typename K::Point_3(p.x(), p.y(), p.z());
}

// CGAL's orientation(p, q, r, s) is the sign of det[q-p, r-p, s-p]; ours is -1 times that.
inline int cgal_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return -static_cast<int>(CGAL::orientation(to_cgal<Epick>(a), to_cgal<Epick>(b),
                                             to_cgal<Epick>(c), to_cgal<Epick>(d)));
}

// A closed triangle as CGAL sees it: a triangle, or (zero area) the segment between its two
// farthest vertices, or a point. Intersection over the three cases, decided by CGAL exactly.
struct CgalSimplex {
  int dim = 2;  // 2 triangle, 1 segment, 0 point
  Epick::Point_3 p[3];
};

inline CgalSimplex cgal_simplex(const Vec3& a, const Vec3& b, const Vec3& c) {
  CgalSimplex s;
  s.p[0] = to_cgal<Epick>(a);
  s.p[1] = to_cgal<Epick>(b);
  s.p[2] = to_cgal<Epick>(c);
  if (!CGAL::collinear(s.p[0], s.p[1], s.p[2])) return s;
  // Collinear: the two extreme points (lexicographic order is monotone along a line).
  std::array<Epick::Point_3, 3> sorted{s.p[0], s.p[1], s.p[2]};
  std::sort(sorted.begin(), sorted.end());
  s.p[0] = sorted[0];
  s.p[1] = sorted[2];
  s.dim = sorted[0] == sorted[2] ? 0 : 1;
  return s;
}

inline bool cgal_intersect(const CgalSimplex& a, const CgalSimplex& b) {
  using K = Epick;
  if (a.dim < b.dim) return cgal_intersect(b, a);
  const K::Triangle_3 ta(a.p[0], a.p[1], a.p[2]);
  const K::Segment_3 sa(a.p[0], a.p[1]), sb(b.p[0], b.p[1]);
  if (a.dim == 2) {
    if (b.dim == 2) return CGAL::do_intersect(ta, K::Triangle_3(b.p[0], b.p[1], b.p[2]));
    if (b.dim == 1) return CGAL::do_intersect(ta, sb);
    return ta.has_on(b.p[0]);
  }
  if (a.dim == 1) return b.dim == 1 ? CGAL::do_intersect(sa, sb) : sa.has_on(b.p[0]);
  return a.p[0] == b.p[0];
}

inline bool cgal_triangles_intersect(const Triangle& a, const Triangle& b) {
  return cgal_intersect(cgal_simplex(a[0], a[1], a[2]), cgal_simplex(b[0], b[1], b[2]));
}

// Exact squared distance between closed triangles (or their degenerate simplices), rounded once.
inline double cgal_triangle_distance(const Triangle& a, const Triangle& b) {
  using K = Epeck;
  auto obj = [](const Triangle& t) {
    const CgalSimplex s = cgal_simplex(t[0], t[1], t[2]);
    return s;
  };
  const CgalSimplex sa = obj(a), sb = obj(b);
  auto P = [](const Epick::Point_3& p) { return K::Point_3(p.x(), p.y(), p.z()); };
  auto sq = [&](const CgalSimplex& x, const CgalSimplex& y) -> K::FT {
    const K::Point_3 x0 = P(x.p[0]), x1 = P(x.p[1]), x2 = P(x.p[2]);
    const K::Point_3 y0 = P(y.p[0]), y1 = P(y.p[1]), y2 = P(y.p[2]);
    if (x.dim == 2 && y.dim == 2) return CGAL::squared_distance(K::Triangle_3(x0, x1, x2), K::Triangle_3(y0, y1, y2));
    if (x.dim == 2 && y.dim == 1) {
      // No direct CGAL routine: 0 if they meet, else an end point against the face or the
      // segment against an edge realises the minimum.
      const K::Triangle_3 t(x0, x1, x2);
      const K::Segment_3 s(y0, y1);
      if (CGAL::do_intersect(t, s)) return K::FT(0);
      K::FT best = CGAL::squared_distance(t, y0);
      best = CGAL::min(best, CGAL::squared_distance(t, y1));
      best = CGAL::min(best, CGAL::squared_distance(s, K::Segment_3(x0, x1)));
      best = CGAL::min(best, CGAL::squared_distance(s, K::Segment_3(x1, x2)));
      return CGAL::min(best, CGAL::squared_distance(s, K::Segment_3(x2, x0)));
    }
    if (x.dim == 2) return CGAL::squared_distance(K::Triangle_3(x0, x1, x2), y0);
    if (x.dim == 1 && y.dim == 1) return CGAL::squared_distance(K::Segment_3(x0, x1), K::Segment_3(y0, y1));
    if (x.dim == 1) return CGAL::squared_distance(K::Segment_3(x0, x1), y0);
    return CGAL::squared_distance(x0, y0);
  };
  const K::FT d2 = sa.dim >= sb.dim ? sq(sa, sb) : sq(sb, sa);
  return std::sqrt(CGAL::to_double(d2));
}

inline double cgal_segment_distance(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2) {
  using K = Epeck;
  const K::Segment_3 a(to_cgal<K>(p1), to_cgal<K>(p2)), b(to_cgal<K>(q1), to_cgal<K>(q2));
  return std::sqrt(CGAL::to_double(CGAL::squared_distance(a, b)));
}

}  // namespace bvh_collision::test
