// A link's proxy level against the octree with its distance field: the pair the tolerance policy
// lets answer a boolean state check against the octree at a tolerance of at least half the level
// (narrowphase/tolerance_policy.h). The field's bound prunes spheres; its occupancy grid answers a
// leaf; the octree is descended only for a contact.
#pragma once

#include <optional>

#include "bvh_collision/narrowphase/link_proxy.h"
#include "bvh_collision/narrowphase/shape_octree.h"
#include "bvh_collision/octree/distance_field.h"

namespace bvh_collision {

// Does a leaf sphere of the proxy (posed at `pose`), grown by `padding`, meet an occupied cube?
// `hit` puts the link within padding + level / 2 of one; false proves it farther than padding.
// With `contact_wanted`, a hit comes with an occupied cube within the leaf's ball and the point of
// the ball nearest it (the octree descended there); without, the field's grid answers where it
// covers the ball, and a contact comes only where the octree had to be descended.
struct ProxyOctreeHit {
  bool hit = false;
  std::optional<OctreeContact> contact;
};
ProxyOctreeHit proxy_meets_octree(const LinkProxy& proxy, const Transform& pose, double padding, const Octree& tree,
                                  const OctreeDistanceField& field, bool contact_wanted);

}  // namespace bvh_collision
