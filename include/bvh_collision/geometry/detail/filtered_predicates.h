// The filtered predicates inline, for the core's own translation units (built with
// -ffp-contract=off: the filters' error bounds assume every product and sum is rounded as
// written). Not API: predicates.h gives the same predicates compiled, for everyone else.
#pragma once

#include <cmath>

#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision::detail {

// The exact signs by expansion arithmetic (predicates.cpp), for what the filters leave undecided.
int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy);

// Sign of det[a-d; b-d; c-d] = (a-d) . ((b-d) x (c-d)): +1, 0 (coplanar) or -1.
inline int orient3d_filtered(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double adx = a.x() - d.x(), bdx = b.x() - d.x(), cdx = c.x() - d.x();
  const double ady = a.y() - d.y(), bdy = b.y() - d.y(), cdy = c.y() - d.y();
  const double adz = a.z() - d.z(), bdz = b.z() - d.z(), cdz = c.z() - d.z();
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  // Shewchuk's o3derrboundA = (7 + 56 eps) eps with eps = 2^-53.
  constexpr double kEps = 1.1102230246251565e-16;
  constexpr double kBound = (7.0 + 56.0 * kEps) * kEps;
  if (det > kBound * permanent) return 1;
  if (-det > kBound * permanent) return -1;
  return orient3d_exact(a, b, c, d);
}

// Sign of the 2-D orientation of (a, b, c) projected by dropping coordinate `drop`; the two kept
// coordinates are taken in cyclic order ((drop+1)%3, (drop+2)%3), so the sign equals the sign of
// component `drop` of (b-a) x (c-a).
inline int orient2d_filtered(const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
  const int i = (drop + 1) % 3, j = (drop + 2) % 3;
  const double acx = a[i] - c[i], bcx = b[i] - c[i];
  const double acy = a[j] - c[j], bcy = b[j] - c[j];
  const double left = acx * bcy, right = acy * bcx;
  const double det = left - right;
  constexpr double kEps = 1.1102230246251565e-16;
  constexpr double kBound = (3.0 + 16.0 * kEps) * kEps;  // Shewchuk's ccwerrboundA
  const double bound = kBound * (std::abs(left) + std::abs(right));
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return orient2d_exact(a[i], a[j], b[i], b[j], c[i], c[j]);
}

// TrianglePlane's construction and side test (see predicates.h).
inline TrianglePlane plane_of(const Vec3& t0, const Vec3& t1, const Vec3& t2) {
  const Vec3 e1 = t1 - t0, e2 = t2 - t0;
  TrianglePlane p;
  p.origin = t0;
  p.normal = Vec3(e1.y() * e2.z() - e1.z() * e2.y(), e1.z() * e2.x() - e1.x() * e2.z(),
                  e1.x() * e2.y() - e1.y() * e2.x());
  p.minors = Vec3(std::abs(e1.y() * e2.z()) + std::abs(e1.z() * e2.y()),
                  std::abs(e1.z() * e2.x()) + std::abs(e1.x() * e2.z()),
                  std::abs(e1.x() * e2.y()) + std::abs(e1.y() * e2.x()));
  return p;
}

inline int plane_side(const TrianglePlane& plane, const Vec3& v) {
  const Vec3 d = v - plane.origin;
  const Vec3& n = plane.normal;
  const double det = n.x() * d.x() + n.y() * d.y() + n.z() * d.z();
  const Vec3& m = plane.minors;
  const double permanent = m.x() * std::abs(d.x()) + m.y() * std::abs(d.y()) + m.z() * std::abs(d.z());
  constexpr double kBound = 8.0 * 1.1102230246251565e-16;  // >= (7 + 56 eps) eps
  if (det > kBound * permanent) return 1;
  if (-det > kBound * permanent) return -1;
  return 0;
}

inline bool plane_separates(const TrianglePlane& plane, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int s = plane_side(plane, a);
  return s != 0 && plane_side(plane, b) == s && plane_side(plane, c) == s;
}

}  // namespace bvh_collision::detail
