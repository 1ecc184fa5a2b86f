// One shape alone: a point against it, a ray into it, and its extent in its body's frame, each
// dispatched over the shape's kind here (narrowphase/shape.h) so that callers never test it.
#pragma once

#include <limits>

#include "bvh_collision/bvh/volumes/aabb.h"
#include "bvh_collision/geometry/types.h"
#include "bvh_collision/narrowphase/shape.h"

namespace bvh_collision {

// Is the world point `p` on the shape (pose in world) or within `padding` of it? A point exactly
// at the padding counts. A closed mesh and a primitive are solids: a point inside is on them.
bool shape_holds_point(const ShapeRef& shape, const Transform& pose, const Vec3& p, double padding);

// Where the ray origin + s * unit (unit length) first meets the shape for s in [0, length], or
// infinity. A ray that starts inside a primitive meets it at 0; a mesh is met at a triangle.
double shape_ray_entry(const ShapeRef& shape, const Transform& pose, const Vec3& origin, const Vec3& unit, double length);

// The shape's points in its body's frame are within this box (a primitive: its bounding ball's
// box; a mesh: its vertices' box) ...
void extend_by_shape(const BodyShape& s, Aabb& box);
// ... and within this distance of `c` (body frame).
double shape_reach(const BodyShape& s, const Vec3& c);

}  // namespace bvh_collision
