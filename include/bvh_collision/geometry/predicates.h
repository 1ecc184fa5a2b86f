// Exact geometric predicates on double coordinates.
//
// The floating-point contract: the filters below hold only when the compiler keeps every product
// and sum as written (no FMA contraction, which the core is built with: -ffp-contract=off). So no
// filtered arithmetic lives in this header: a package that includes it and compiles with
// -ffp-contract=fast -mfma calls the core's own compiled code. The core inlines the same filters
// from geometry/detail/filtered_predicates.h, which is not API.
//
// Each predicate first evaluates its determinant in floating point with a forward error bound
// (Shewchuk's static filter); only when the value is within the bound of zero does it recompute
// the sign exactly with expansion arithmetic (error-free sums and products). The sign returned is
// always the sign of the exact determinant of the given doubles: there is no epsilon.
#pragma once

#include <cmath>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// Sign of det[a-d; b-d; c-d] = (a-d) . ((b-d) x (c-d)): +1, 0 (coplanar) or -1.
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

// Sign of the 2-D orientation of (a, b, c) projected by dropping coordinate `drop`; the two kept
// coordinates are taken in cyclic order ((drop+1)%3, (drop+2)%3), so the sign equals the sign of
// component `drop` of (b-a) x (c-a).
int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop);

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

  static TrianglePlane of(const Vec3& t0, const Vec3& t1, const Vec3& t2);
  // +1 / -1 when the side of v is certain, 0 when it is not (on the plane, or too close to tell).
  int side(const Vec3& v) const;
  // True when all three points are certainly strictly on one side: the triangles cannot meet.
  bool separates(const Vec3& a, const Vec3& b, const Vec3& c) const;
};

}  // namespace bvh_collision
