// Euclidean distances between points, segments and triangles, with witness points.
//
// All routines work relative to a local origin near the geometry (the first vertex), so a scene
// translated far from the origin gives the same answer. Triangle-triangle distance is exactly 0
// when the exact intersection test says the triangles touch.
#pragma once

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

struct ClosestPoints {
  double distance = 0.0;
  Vec3 on_a = Vec3::Zero();  // witness point on the first argument
  Vec3 on_b = Vec3::Zero();  // witness point on the second argument
};

// Closest point to p on closed segment (a, b) (possibly a point).
Vec3 closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b);

// Closest point to p on closed triangle (a, b, c) (possibly degenerate).
Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c);

// Whether the triangle's plane lies farther than `limit` from p by much more than the rounding of
// either distance (a billionth of the sizes involved), so that
// |closest_point_on_triangle(p, a, b, c) - p| >= limit as computed: a query that wants only the
// triangles closer than a limit skips the others at a fifth of the closest point's cost. False for
// a degenerate triangle, a limit that is infinite or not a number.
bool triangle_plane_beyond(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double limit);

// Closed segments (p1, p2) and (q1, q2); stays correct for parallel and nearly parallel segments
// (the candidates include every end point against the other segment).
ClosestPoints segment_segment_distance(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2);

ClosestPoints triangle_triangle_distance(const Triangle& a, const Triangle& b);

// A point common to two intersecting triangles (approximate: for contact reporting).
Vec3 intersection_point(const Triangle& a, const Triangle& b);

}  // namespace bvh_collision
