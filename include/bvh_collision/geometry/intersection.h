// Exact intersection tests between closed triangles and segments.
//
// Every decision is the sign of an exact orient3d/orient2d (geometry/predicates.h), so results
// are exact for the given double coordinates: touching counts as intersecting; coplanar, shared
// edge, shared vertex and vertex-on-face cases are decided exactly; a zero-area triangle is
// treated as the segment (or point) it is, and still intersects what that segment touches.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// Closed triangles (a0, a1, a2) and (b0, b1, b2), either possibly degenerate.
bool triangles_intersect(const Vec3& a0, const Vec3& a1, const Vec3& a2, const Vec3& b0,
                         const Vec3& b1, const Vec3& b2);

inline bool triangles_intersect(const Triangle& a, const Triangle& b) {
  return triangles_intersect(a[0], a[1], a[2], b[0], b[1], b[2]);
}

// Closed segment (u, v) (possibly a point) against closed triangle (a, b, c) (possibly degenerate).
bool segment_intersects_triangle(const Vec3& u, const Vec3& v, const Vec3& a, const Vec3& b,
                                 const Vec3& c);

// Closed segments (possibly points) in 3-D.
bool segments_intersect(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2);

// Where the ray origin + s * unit (unit length), 0 <= s <= length, first meets the closed ball:
// 0 when the origin is inside, infinity when it misses.
inline double ray_ball_entry(const Vec3& origin, const Vec3& unit, double length, const Vec3& centre, double radius) {
  const Vec3 m = origin - centre;
  const double b = m.dot(unit), c = m.squaredNorm() - radius * radius;
  if (c <= 0.0) return 0.0;
  const double disc = b * b - c;
  if (b > 0.0 || disc < 0.0) return std::numeric_limits<double>::infinity();
  const double s = -b - std::sqrt(disc);
  return s <= length ? s : std::numeric_limits<double>::infinity();
}

// Closed sphere against closed axis-aligned box, exactly as the geometry is: the squared distance
// from the centre to the box is at most r^2. (The textbook's "distance between the centres <= r"
// misses a sphere touching a large box's face, and accepts nothing it should not only by luck.)
inline bool sphere_intersects_box(const Vec3& centre, double r, const Vec3& box_min, const Vec3& box_max) {
  double d2 = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double excess = std::max(box_min[i] - centre[i], 0.0) + std::max(centre[i] - box_max[i], 0.0);
    d2 += excess * excess;
  }
  return d2 <= r * r;
}

}  // namespace bvh_collision
