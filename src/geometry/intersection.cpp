#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/geometry/detail/filtered_predicates.h"

#include <algorithm>

#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision {
namespace {

// The filtered predicates inlined (geometry/detail/filtered_predicates.h), under short names.
constexpr auto orient3 = detail::orient3d_filtered;
constexpr auto orient2 = detail::orient2d_filtered;

// ---- 2-D tests in the projection that drops coordinate k (injective on the plane in question).

// q lies in the bounding box of segment (p1, p2) in the projection; with collinearity known,
// this means q is on the closed segment.
bool within_box_2d(const Vec3& p1, const Vec3& p2, const Vec3& q, int k) {
  for (int axis : {(k + 1) % 3, (k + 2) % 3}) {
    if (q[axis] < std::min(p1[axis], p2[axis]) || q[axis] > std::max(p1[axis], p2[axis])) {
      return false;
    }
  }
  return true;
}

bool segments_intersect_2d(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2, int k) {
  const int o1 = orient2(p1, p2, q1, k), o2 = orient2(p1, p2, q2, k);
  const int o3 = orient2(q1, q2, p1, k), o4 = orient2(q1, q2, p2, k);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && within_box_2d(p1, p2, q1, k)) || (o2 == 0 && within_box_2d(p1, p2, q2, k)) ||
         (o3 == 0 && within_box_2d(q1, q2, p1, k)) || (o4 == 0 && within_box_2d(q1, q2, p2, k));
}

// Closed, non-degenerate (in this projection) triangle.
bool point_in_triangle_2d(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, int k) {
  const int o1 = orient2(a, b, p, k), o2 = orient2(b, c, p, k), o3 = orient2(c, a, p, k);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

bool segment_hits_triangle_2d(const Vec3& u, const Vec3& v, const Vec3& a, const Vec3& b,
                              const Vec3& c, int k) {
  return point_in_triangle_2d(u, a, b, c, k) || segments_intersect_2d(u, v, a, b, k) ||
         segments_intersect_2d(u, v, b, c, k) || segments_intersect_2d(u, v, c, a, k);
}

bool triangles_intersect_2d(const Vec3* a, const Vec3* b, int k) {
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (segments_intersect_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3], k)) return true;
    }
  }
  return point_in_triangle_2d(a[0], b[0], b[1], b[2], k) ||
         point_in_triangle_2d(b[0], a[0], a[1], a[2], k);
}

// ---- 3-D building blocks.

// The line through u and v (not in the triangle's plane) passes through closed triangle abc.
bool line_crosses_triangle(const Vec3& u, const Vec3& v, const Vec3& a, const Vec3& b, const Vec3& c) {
  const int o1 = orient3(u, v, a, b), o2 = orient3(u, v, b, c), o3 = orient3(u, v, c, a);
  return (o1 >= 0 && o2 >= 0 && o3 >= 0) || (o1 <= 0 && o2 <= 0 && o3 <= 0);
}

// Segment uv against non-degenerate triangle abc whose plane sides su, sv are known.
bool segment_triangle_with_sides(const Vec3& u, const Vec3& v, int su, int sv, const Vec3& a,
                                 const Vec3& b, const Vec3& c) {
  if (su * sv > 0) return false;
  if (su == 0 && sv == 0) return segment_hits_triangle_2d(u, v, a, b, c, projection_axis(a, b, c));
  return line_crosses_triangle(u, v, a, b, c);
}

// A degenerate triangle is the union of its three edges.
bool degenerate_vs_geometry(const Vec3* d, const Vec3* other, bool other_degenerate) {
  for (int i = 0; i < 3; ++i) {
    const Vec3& u = d[i];
    const Vec3& v = d[(i + 1) % 3];
    if (other_degenerate) {
      for (int j = 0; j < 3; ++j) {
        if (segments_intersect(u, v, other[j], other[(j + 1) % 3])) return true;
      }
    } else if (segment_intersects_triangle(u, v, other[0], other[1], other[2])) {
      return true;
    }
  }
  return false;
}

// Both triangles in one plane, or at least one degenerate: decided without the fast path.
bool triangles_intersect_special(const Vec3* a, const Vec3* b) {
  const bool a_degenerate = projection_axis(a[0], a[1], a[2]) < 0;
  const bool b_degenerate = projection_axis(b[0], b[1], b[2]) < 0;
  if (a_degenerate) return degenerate_vs_geometry(a, b, b_degenerate);
  if (b_degenerate) return degenerate_vs_geometry(b, a, false);
  return triangles_intersect_2d(a, b, projection_axis(b[0], b[1], b[2]));
}

}  // namespace

bool segments_intersect(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2) {
  if (orient3(p1, p2, q1, q2) != 0) return false;  // not coplanar
  // Coplanar: find a projection that is injective on the common plane (some non-collinear triple
  // keeps non-zero area in it).
  const Vec3* pts[4] = {&p1, &p2, &q1, &q2};
  for (int k = 0; k < 3; ++k) {
    for (int skip = 0; skip < 4; ++skip) {
      const Vec3* t[3];
      for (int i = 0, n = 0; i < 4; ++i) {
        if (i != skip) t[n++] = pts[i];
      }
      if (orient2(*t[0], *t[1], *t[2], k) != 0) return segments_intersect_2d(p1, p2, q1, q2, k);
    }
  }
  // All four points on one line: compare intervals along a coordinate that varies on it (an
  // affine function of the line parameter, hence order-preserving).
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = std::min({p1[axis], p2[axis], q1[axis], q2[axis]});
    const double hi = std::max({p1[axis], p2[axis], q1[axis], q2[axis]});
    if (lo == hi) continue;
    return std::max(std::min(p1[axis], p2[axis]), std::min(q1[axis], q2[axis])) <=
           std::min(std::max(p1[axis], p2[axis]), std::max(q1[axis], q2[axis]));
  }
  return true;  // all four points coincide
}

bool segment_intersects_triangle(const Vec3& u, const Vec3& v, const Vec3& a, const Vec3& b,
                                 const Vec3& c) {
  if (projection_axis(a, b, c) < 0) {
    const Vec3 tri[3] = {a, b, c};
    const Vec3 seg[3] = {u, v, v};  // a segment as a degenerate triangle
    return degenerate_vs_geometry(tri, seg, true);
  }
  const int su = orient3(a, b, c, u), sv = orient3(a, b, c, v);
  if (u == v) {
    return su == 0 && point_in_triangle_2d(u, a, b, c, projection_axis(a, b, c));
  }
  return segment_triangle_with_sides(u, v, su, sv, a, b, c);
}

bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                         const Vec3& b1, const Vec3& b2) {
  const Vec3 a[3] = {a0, a1, a2};
  const Vec3 b[3] = {b0, b1, b2};
  // Sides of a's vertices against b's plane, and of b's against a's; all on one strict side: apart.
  const int sa[3] = {orient3(b0, b1, b2, a0), orient3(b0, b1, b2, a1), orient3(b0, b1, b2, a2)};
  if (sa[0] * sa[1] > 0 && sa[0] * sa[2] > 0) return false;
  const int sb[3] = {orient3(a0, a1, a2, b0), orient3(a0, a1, a2, b1), orient3(a0, a1, a2, b2)};
  if (sb[0] * sb[1] > 0 && sb[0] * sb[2] > 0) return false;
  // All zero: coplanar, or the other triangle is degenerate (its plane is undefined).
  if ((sa[0] == 0 && sa[1] == 0 && sa[2] == 0) || (sb[0] == 0 && sb[1] == 0 && sb[2] == 0)) {
    return triangles_intersect_special(a, b);
  }
  // Two non-degenerate triangles in distinct planes meet iff an edge of one meets the other:
  // an end point of the common segment on the planes' line lies on an edge of one of them.
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    if (sa[i] * sa[j] <= 0 && segment_triangle_with_sides(a[i], a[j], sa[i], sa[j], b0, b1, b2)) {
      return true;
    }
    if (sb[i] * sb[j] <= 0 && segment_triangle_with_sides(b[i], b[j], sb[i], sb[j], a0, a1, a2)) {
      return true;
    }
  }
  return false;
}

}  // namespace bvh_collision
