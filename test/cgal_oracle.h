// CGAL as the independent oracle for the geometry layer (test-only dependency). The oracle is
// compiled once (cgal_oracle.cpp, the library bvh_collision_cgal_oracle): the tests that ask it
// do not parse or instantiate CGAL themselves, which took most of their compile time.
#pragma once

#include <vector>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision::test {

// The sign of orient3d as ours defines it (geometry/predicates.h): -1 times CGAL's
// orientation(a, b, c, d), which is the sign of det[b-a, c-a, d-a]. Exact.
int cgal_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// CGAL's orientation of a, b, c projected along `axis` onto the plane of the next two
// coordinates ((axis + 1) % 3, (axis + 2) % 3), as our orient2d(a, b, c, axis). Exact.
int cgal_orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int axis);

// Whether two closed triangles meet, a zero-area triangle taken as the segment between its two
// farthest vertices, or a point. Decided exactly.
bool cgal_triangles_intersect(const Triangle& a, const Triangle& b);

// The distance between two closed triangles (degenerate ones as above): the exact squared
// distance, rounded once, then its square root.
double cgal_triangle_distance(const Triangle& a, const Triangle& b);

// The distance between segments [p1, p2] and [q1, q2], exact as above.
double cgal_segment_distance(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2);

// Whether a closed triangle (degenerate ones as above) meets the closed box [lo, hi]. Exact.
bool cgal_triangle_meets_box(const Triangle& t, const Vec3& lo, const Vec3& hi);

// The distance between a closed triangle and the closed box [lo, hi]: 0 when they meet, else the
// nearest of the box's 12 face triangles (apart, the distance is reached on its surface).
double cgal_triangle_box_distance(const Triangle& t, const Vec3& lo, const Vec3& hi);

// The extreme points of a point set (CGAL::extreme_points_3): the vertices of its hull.
std::vector<Vec3> cgal_extreme_points(const std::vector<Vec3>& points);

// The distance between the convex hulls of two point sets (CGAL::Polytope_distance_d, exact
// arithmetic), the exact squared distance's quotient rounded, then its square root.
double cgal_polytope_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b);

}  // namespace bvh_collision::test
