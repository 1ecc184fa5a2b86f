// A link's proxy level against the octree with its distance field (narrowphase/proxy_octree.h).
#include "bvh_collision/narrowphase/proxy_octree.h"

#include <optional>
#include <vector>

#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {

// A leaf sphere meets the octree when one occupied cube meets it (exact: the field's grid says
// no, the octree says yes and gives the contact); a sphere above the leaves only needs the
// distance field's bound not to clear it.
ProxyOctreeHit proxy_meets_octree(const LinkProxy& proxy, const Transform& pose, double padding, const Octree& tree,
                                  const OctreeDistanceField& field, bool contact_wanted) {
  std::vector<Octree::Leaf> cubes;
  Vec3 centre = Vec3::Zero();
  bool grid_says = false;
  const bool hit = proxy_meets_obstacle(proxy, pose, padding, [&](const Vec3& c, double r, bool leaf) {
    if (field.lower_bound(c) > grown_radius(r)) return false;
    if (!leaf) return true;
    // The field's grid knows the occupied voxels near the robot (the same octree revision): one
    // scan of a few rows instead of a descent of the octree, which only a contact needs.
    const std::optional<bool> meets = field.ball_meets_occupied(c, r);
    if (meets && !*meets) return false;
    if (meets && !contact_wanted) return grid_says = true;
    cubes = tree.occupied_in_sphere(c, r, true);
    centre = c;
    return !cubes.empty();
  });
  if (!hit || grid_says) return {hit, std::nullopt};
  const Vec3 lo = tree.cube_min(cubes.front().key), hi = lo + Vec3::Constant(tree.cube_size(cubes.front().depth));
  return {true, OctreeContact{cubes.front(), centre.cwiseMax(lo).cwiseMin(hi)}};
}

}  // namespace bvh_collision
