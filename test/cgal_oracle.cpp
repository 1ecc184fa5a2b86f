#include "cgal_oracle.h"

#include "bvh_collision/geometry/mesh.h"

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Gmpzf.h>
#include <CGAL/Polytope_distance_d.h>
#include <CGAL/Polytope_distance_d_traits_3.h>
#include <CGAL/convex_hull_3.h>
#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>

namespace bvh_collision::test {
namespace {

using Epick = CGAL::Exact_predicates_inexact_constructions_kernel;
using Epeck = CGAL::Exact_predicates_exact_constructions_kernel;

template <class K>
typename K::Point_3 to_cgal(const Vec3& p) {
  return typename K::Point_3(p.x(), p.y(), p.z());
}

// A closed triangle as CGAL sees it: a triangle, or (zero area) the segment between its two
// farthest vertices, or a point.
struct CgalSimplex {
  int dim = 2;  // 2 triangle, 1 segment, 0 point
  Epick::Point_3 p[3];
};

CgalSimplex cgal_simplex(const Vec3& a, const Vec3& b, const Vec3& c) {
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

bool cgal_intersect(const CgalSimplex& a, const CgalSimplex& b) {
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

// The exact squared distance of two simplices, the first of dimension at least the second's.
Epeck::FT squared_distance(const CgalSimplex& x, const CgalSimplex& y) {
  using K = Epeck;
  const auto P = [](const Epick::Point_3& p) { return K::Point_3(p.x(), p.y(), p.z()); };
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
}

}  // namespace

int cgal_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return -static_cast<int>(CGAL::orientation(to_cgal<Epick>(a), to_cgal<Epick>(b), to_cgal<Epick>(c), to_cgal<Epick>(d)));
}

int cgal_orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int axis) {
  using P2 = Epick::Point_2;
  const int x = (axis + 1) % 3, y = (axis + 2) % 3;
  return static_cast<int>(CGAL::orientation(P2(a[x], a[y]), P2(b[x], b[y]), P2(c[x], c[y])));
}

bool cgal_triangles_intersect(const Triangle& a, const Triangle& b) {
  return cgal_intersect(cgal_simplex(a[0], a[1], a[2]), cgal_simplex(b[0], b[1], b[2]));
}

double cgal_triangle_distance(const Triangle& a, const Triangle& b) {
  const CgalSimplex sa = cgal_simplex(a[0], a[1], a[2]), sb = cgal_simplex(b[0], b[1], b[2]);
  const Epeck::FT d2 = sa.dim >= sb.dim ? squared_distance(sa, sb) : squared_distance(sb, sa);
  return std::sqrt(CGAL::to_double(d2));
}

double cgal_segment_distance(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2) {
  using K = Epeck;
  const K::Segment_3 a(to_cgal<K>(p1), to_cgal<K>(p2)), b(to_cgal<K>(q1), to_cgal<K>(q2));
  return std::sqrt(CGAL::to_double(CGAL::squared_distance(a, b)));
}

bool cgal_triangle_meets_box(const Triangle& t, const Vec3& lo, const Vec3& hi) {
  const Epick::Iso_cuboid_3 box(to_cgal<Epick>(lo), to_cgal<Epick>(hi));
  const CgalSimplex s = cgal_simplex(t[0], t[1], t[2]);
  if (s.dim == 2) return CGAL::do_intersect(Epick::Triangle_3(s.p[0], s.p[1], s.p[2]), box);
  if (s.dim == 1) return CGAL::do_intersect(Epick::Segment_3(s.p[0], s.p[1]), box);
  return !box.has_on_unbounded_side(s.p[0]);
}

double cgal_triangle_box_distance(const Triangle& t, const Vec3& lo, const Vec3& hi) {
  if (cgal_triangle_meets_box(t, lo, hi)) return 0.0;
  const TriangleMesh box = box_mesh(hi - lo);
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < box.triangles.size(); ++f) {
    Triangle face = box.triangle(f);
    for (int k = 0; k < 3; ++k) face[k] += 0.5 * (lo + hi);
    best = std::min(best, cgal_triangle_distance(t, face));
  }
  return best;
}

std::vector<Vec3> cgal_extreme_points(const std::vector<Vec3>& points) {
  std::vector<Epick::Point_3> in, extreme;
  for (const Vec3& p : points) in.push_back(to_cgal<Epick>(p));
  CGAL::extreme_points_3(in, std::back_inserter(extreme));
  std::vector<Vec3> out;
  for (const auto& e : extreme) out.emplace_back(e.x(), e.y(), e.z());
  return out;
}

double cgal_polytope_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  using Traits = CGAL::Polytope_distance_d_traits_3<Epick, CGAL::Gmpzf, double>;
  std::vector<Epick::Point_3> pa, pb;
  for (const Vec3& p : a) pa.push_back(to_cgal<Epick>(p));
  for (const Vec3& p : b) pb.push_back(to_cgal<Epick>(p));
  CGAL::Polytope_distance_d<Traits> d(pa.begin(), pa.end(), pb.begin(), pb.end());
  return std::sqrt(CGAL::to_double(d.squared_distance_numerator()) / CGAL::to_double(d.squared_distance_denominator()));
}

}  // namespace bvh_collision::test
