// Certified distance between any two convex sets the checker meets: exact primitives, triangles
// and convex hulls, by GJK on their exact support functions.
//
// What is certified is the lower bound: the gap between the two sets along a direction, computed
// from their support points with a rounding margin, so it never exceeds the true distance however
// GJK ended. The reported distance is that of two witness points, one in each set, so it is never
// below the true distance (up to the rounding of a subtraction). Touching gives a lower bound of 0.
//
// Near contact the direction GJK ends with is only as accurate as the rounding of its simplex
// allows (about 1e-16 x size / distance radians), and a curved surface loses the square of that
// times its size from the gap: two cylinders 1e-12 m apart would not be certified apart. So when a
// curved primitive is involved and the bound is not yet tight, the direction is refined by a
// pattern search on the gap itself, whose evaluation does not cancel: the bound then comes within
// about 1e-14 of the sets' size of the true distance, and "touching" and "1e-12 apart" are told
// apart at robot scales.
#pragma once

#include <limits>

#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/primitives.h"

namespace bvh_collision {

// A convex set in its own frame. Holds a hull by pointer (it must outlive the query).
struct ConvexShape {
  enum class Kind : std::uint8_t { kPrimitive, kTriangle, kHull };
  Kind kind = Kind::kPrimitive;
  Primitive primitive;
  Triangle triangle;
  const ConvexHull* hull = nullptr;

  static ConvexShape of(const Primitive& p) { return {Kind::kPrimitive, p, Triangle{}, nullptr}; }
  static ConvexShape of(const Triangle& t) { return {Kind::kTriangle, Primitive{}, t, nullptr}; }
  static ConvexShape of(const ConvexHull& h) { return {Kind::kHull, Primitive{}, Triangle{}, &h}; }
};

// The largest norm of any point of the set (for rounding margins).
double extent(const ConvexShape& s);

// The two sets' distance, a in its own frame and b placed by `b_in_a`; witnesses in a's frame.
// With `decide_at` (not NaN) the search may stop as soon as it knows whether the distance is at
// most decide_at (distance <= decide_at) or above it (lower_bound > decide_at): a collision test
// with padding decide_at. With a positive `slack` it may stop once distance - lower_bound <= slack
// (a distance wanted within the slack, not to the last digit: GJK creeps towards a curved surface
// for dozens of steps, and the refinement above takes hundreds more). Every result holds
// lower_bound <= true distance <= distance (rounding aside) whenever it stops. With `far_only`,
// decide_at stops the search only when the distance is above it: nearer, it goes on to within the
// slack (one search where a caller wants the distance only when it is near).
ConvexDistance convex_distance(const ConvexShape& a, const ConvexShape& b, const Transform& b_in_a,
                               double decide_at = std::numeric_limits<double>::quiet_NaN(), double slack = 0.0,
                               bool far_only = false);

// The collision decision of docs/design.md for two convex sets with padding: true when the
// distance may be at most `padding` (the certified lower bound does not exceed it).
inline bool convex_within(const ConvexShape& a, const ConvexShape& b, const Transform& b_in_a, double padding) {
  return convex_distance(a, b, b_in_a, padding).lower_bound <= padding;
}

}  // namespace bvh_collision
