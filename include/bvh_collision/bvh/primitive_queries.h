// An exact primitive (sphere, box, cylinder, capsule) against a mesh BVH: the hierarchy descended
// with the primitive's own box, triangles against the primitive by certified convex distance
// (geometry/convex_distance.h). Semantics of queries.h: touching is collision, padding, tolerance,
// solids. A primitive is always a solid: a mesh wholly inside it collides; a primitive wholly
// inside a closed mesh collides when request.solids.
#pragma once

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/primitives.h"

namespace bvh_collision {

// Contacts: positions between the two witnesses, normals from the primitive towards the mesh.
CollisionResult collide(const Bvh<Obb>& mesh, const Transform& pose_mesh, const Primitive& primitive,
                        const Transform& pose_primitive, const CollisionRequest& request = {});

// point_a on the mesh, point_b on the primitive (world). Infinity when nothing is below
// request.upper_bound; with a tolerance at most that much above the true distance.
DistanceResult distance(const Bvh<Obb>& mesh, const Transform& pose_mesh, const Primitive& primitive,
                        const Transform& pose_primitive, const DistanceRequest& request = {});

}  // namespace bvh_collision
