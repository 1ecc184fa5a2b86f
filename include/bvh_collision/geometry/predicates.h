// Exact geometric predicates on double coordinates.
//
// Each predicate first evaluates its determinant in floating point with a forward error bound
// (Shewchuk's static filter); only when the value is within the bound of zero does it recompute
// the sign exactly with expansion arithmetic (error-free sums and products). The sign returned is
// always the sign of the exact determinant of the given doubles: there is no epsilon.
#pragma once

#include <cmath>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

namespace detail {
int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy);
}  // namespace detail

// Sign of det[a-d; b-d; c-d] = (a-d) . ((b-d) x (c-d)): +1, 0 (coplanar) or -1.
inline int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
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
  return detail::orient3d_exact(a, b, c, d);
}

// Sign of the 2-D orientation of (a, b, c) projected by dropping coordinate `drop`; the two kept
// coordinates are taken in cyclic order ((drop+1)%3, (drop+2)%3), so the sign equals the sign of
// component `drop` of (b-a) x (c-a).
inline int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop) {
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
  return detail::orient2d_exact(a[i], a[j], b[i], b[j], c[i], c[j]);
}

// The coordinate to drop so that projecting the plane of (a, b, c) onto the other two is
// injective: one whose exact orient2d is non-zero, preferring the dominant normal component.
// Returns -1 exactly when a, b and c are collinear (the triangle has zero area).
int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c);

}  // namespace bvh_collision

namespace bvh_collision {

// A triangle's plane prepared for many side tests: the sign of det[t1-t0, t2-t0, v-t0] is
// certified in floating point with Shewchuk's orient3d bound, the 2x2 minors of the edge vectors
// computed once. Used to reject triangle pairs quickly; undecided cases go to the exact test.
struct TrianglePlane {
  Vec3 origin = Vec3::Zero();
  Vec3 normal = Vec3::Zero();  // (t1 - t0) x (t2 - t0), not normalised
  Vec3 minors = Vec3::Zero();  // per component, |a*b| + |c*d| of the two products in `normal`

  static TrianglePlane of(const Vec3& t0, const Vec3& t1, const Vec3& t2) {
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
  // +1 / -1 when the side of v is certain, 0 when it is not (on the plane, or too close to tell).
  int side(const Vec3& v) const {
    const Vec3 d = v - origin;
    const double det = normal.x() * d.x() + normal.y() * d.y() + normal.z() * d.z();
    const double permanent = minors.x() * std::abs(d.x()) + minors.y() * std::abs(d.y()) + minors.z() * std::abs(d.z());
    constexpr double kBound = 8.0 * 1.1102230246251565e-16;  // >= (7 + 56 eps) eps
    if (det > kBound * permanent) return 1;
    if (-det > kBound * permanent) return -1;
    return 0;
  }
  // True when all three points are certainly strictly on one side: the triangles cannot meet.
  bool separates(const Vec3& a, const Vec3& b, const Vec3& c) const {
    const int s = side(a);
    return s != 0 && side(b) == s && side(c) == s;
  }
};

}  // namespace bvh_collision
