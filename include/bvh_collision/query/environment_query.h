// The robot against its environment (CollisionChecker::check_environment): request and result.
#pragma once

#include <limits>
#include <string>
#include <vector>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/types.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

struct EnvironmentRequest {
  double tolerance = 0.0;  // docs/design.md
  bool all_links = false;  // false: stop at the first colliding link
  bool distance = false;   // also the minimum distance from the robot to any obstacle
  bool solids = true;      // closed meshes bound solids; occupied space is solid
  bool octree = true;      // check against the octree...
  bool objects = true;     // ...and against the collision objects
  // False: the boolean answer is all the caller reads (check_batch), so a proxy check may answer
  // from the distance field's occupancy grid without finding the octree cube for a contact.
  bool contacts = true;
  Transform root_pose;     // the root link in the environment's (world) frame: a moving base
  // Per link, nonzero: check it; null: every link (check_batch checks the links no joint moves
  // once per batch). Not owned: it must outlive the query.
  const std::vector<char>* only_links = nullptr;
  // Boolean checks: a link whose bounding sphere the octree's distance field clears (the field
  // proves every occupied cube farther than its radius + padding) skips the octree, and at a
  // tolerance a proxy level fits, the link's proxy spheres answer against the field and its grid
  // (within padding + level / 2). The field covers the robot's reach around the root; it is
  // kept until the octree changes (Environment::octree_distance_field; its build time and size:
  // docs/performance.md). kIfKept (the default) uses one already built
  // (CollisionChecker::prepare_distance_field, which the node calls after each map change);
  // kBuild builds it if needed; kOff never uses it. Exact answers are unchanged by it.
  enum class DistanceField { kOff, kIfKept, kBuild };
  DistanceField distance_field = DistanceField::kIfKept;
};

struct EnvironmentContact {
  int link = -1;
  std::string object;            // the object's id; empty for the octree
  Octree::Leaf voxel;            // the occupied cube, for the octree
  Vec3 position = Vec3::Zero();  // world frame
};

struct EnvironmentResult {
  bool collision = false;
  std::vector<EnvironmentContact> contacts;  // one per colliding (link, obstacle), in checking order
  double min_distance = std::numeric_limits<double>::quiet_NaN();  // only when asked; inf: no obstacle
  int closest_link = -1;
  std::string closest_object;  // empty: the octree (when closest_link >= 0)
  Octree::Leaf closest_voxel;
  Vec3 point_link = Vec3::Zero(), point_obstacle = Vec3::Zero();  // world frame witnesses
  QueryStats stats;
};

}  // namespace bvh_collision
