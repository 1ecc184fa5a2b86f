// Two placed shapes (a link's collision element or a collision object) against each other:
// collision and distance with witnesses, through one dispatch table over the pair of shape kinds
// (narrowphase/shape.h) instead of a type test in each query.
#pragma once

#include <vector>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/narrowphase/shape.h"

namespace bvh_collision {

struct PairRequest {
  double padding = 0.0;          // the pair collides when its distance is at most this
  double tolerance = 0.0;        // docs/design.md
  std::size_t max_contacts = 0;  // contacts wanted (0: a boolean answer)
  bool solids = true;            // closed meshes bound solids
};

// Contacts (world frame) go to `contacts` when it is not null, normals from b towards a.
bool shapes_collide(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                    const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats);

// The distance when below `best` (else `best` or more); with a tolerance, at most that much above
// the true distance. Witnesses wa (on a) and wb (on b) in the world frame.
double shapes_distance(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double best,
                       bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance = 0.0);

}  // namespace bvh_collision
