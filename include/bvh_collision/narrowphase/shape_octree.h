// A shape against the occupied cubes of the environment octree, the octree being one more kind of
// the narrowphase: shape_meets_octree and shape_octree_distance dispatch over the shape's kind (a
// mesh: the BVH and the octree descended together, cube against volume, then cube against
// triangle, exactly; a primitive: certified convex distance against each nearby cube; a sphere:
// the octree's own sphere query and nearest-cube search). Semantics of
// docs/design.md: touching is collision, padding p, tolerance eps, and solids: a link inside
// occupied space, or an occupied cube inside a closed link, is in collision (distance 0).
#pragma once

#include <limits>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/narrowphase/shape.h"
#include "bvh_collision/narrowphase/shape_pairs.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

struct OctreeContact {
  Octree::Leaf voxel;            // the occupied leaf (a voxel or a pruned cube)
  Vec3 position = Vec3::Zero();  // world frame, a point of the link within padding of the cube
};

struct OctreeDistance {
  double distance = std::numeric_limits<double>::infinity();  // inf: nothing below upper_bound
  Vec3 on_link = Vec3::Zero(), on_cube = Vec3::Zero();        // world-frame witnesses
  Octree::Leaf voxel;
};

// The pair calling convention of shape_pairs.h, the octree the second shape (its pose the world):
// does the shape come within request.padding of an occupied cube? With a tolerance it may also
// answer yes up to padding + tolerance, never no below padding; `contact` (when not null) gets the
// cube and a point of the shape within padding of it. (request.max_contacts is not read: one
// contact, the cube's.)
bool shape_meets_octree(const ShapeRef& shape, const Transform& pose, const Octree& tree, const PairRequest& request,
                        OctreeContact* contact, QueryStats& stats);

// The distance from the shape to the nearest occupied cube, if below `upper_bound` (else
// infinity), with witnesses.
OctreeDistance shape_octree_distance(const ShapeRef& shape, const Transform& pose, const Octree& tree, bool solids,
                                     double upper_bound, QueryStats& stats);

// The kinds, for the dispatch above and their tests.

// Does the mesh (pose in world) come within `padding` of an occupied cube? With tolerance > 0
// it may also answer yes up to padding + tolerance, never no below padding.
bool mesh_meets_octree(const Bvh<Obb>& mesh, const Transform& pose, const Octree& tree, double padding,
                       double tolerance, bool solids, OctreeContact* contact = nullptr, QueryStats* stats = nullptr);

// The distance from the mesh to the nearest occupied cube, if below `upper_bound`.
OctreeDistance mesh_octree_distance(const Bvh<Obb>& mesh, const Transform& pose, const Octree& tree, bool solids,
                                    double upper_bound = std::numeric_limits<double>::infinity(),
                                    QueryStats* stats = nullptr);

// The same for a point (a sphere link is a point with its radius subtracted).
OctreeDistance point_octree_distance(const Vec3& p, const Octree& tree,
                                     double upper_bound = std::numeric_limits<double>::infinity());

// The same for an exact primitive (cylinder, box, capsule; a sphere too, though the checker asks
// the octree's sphere query for those): certified convex distance against each nearby cube.
bool primitive_meets_octree(const Primitive& primitive, const Transform& pose, const Octree& tree, double padding,
                            OctreeContact* contact = nullptr, QueryStats* stats = nullptr);
OctreeDistance primitive_octree_distance(const Primitive& primitive, const Transform& pose, const Octree& tree,
                                         double upper_bound = std::numeric_limits<double>::infinity(),
                                         QueryStats* stats = nullptr);

// Exact primitives, exposed for their tests: a closed triangle against a closed axis-aligned box.
bool triangle_meets_box(const Triangle& t, const Vec3& lo, const Vec3& hi);
double triangle_box_distance(const Triangle& t, const Vec3& lo, const Vec3& hi, Vec3& on_triangle, Vec3& on_box);

}  // namespace bvh_collision
