// Exact intersection tests between closed triangles and segments.
//
// Every decision is the sign of an exact orient3d/orient2d (geometry/predicates.h), so results
// are exact for the given double coordinates: touching counts as intersecting; coplanar, shared
// edge, shared vertex and vertex-on-face cases are decided exactly; a zero-area triangle is
// treated as the segment (or point) it is, and still intersects what that segment touches.
#pragma once

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

}  // namespace bvh_collision
