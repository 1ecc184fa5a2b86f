// The self-collision query (CollisionChecker::check_self): its request and result.
#pragma once

#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

struct SelfCollisionRequest {
  // docs/design.md. With `distance`, the reported minimum distance may also exceed the true
  // one by up to this much (never fall below it): the search prunes what cannot gain more.
  double tolerance = 0.0;
  bool all_pairs = false;        // false: stop at the first colliding pair
  std::size_t max_contacts = 0;  // contacts per colliding pair (0: none)
  bool distance = false;         // also the minimum distance over checked pairs
  bool solids = true;            // closed meshes bound solids
  // Only these checked pairs (indices into CollisionChecker::checked_pairs(), e.g. from
  // pairs_moved_by); null: all of them. Not owned: it must outlive the query.
  const std::vector<std::size_t>* only_pairs = nullptr;
};

struct LinkContact {
  int link_a = -1, link_b = -1;
  MeshContact contact;
};

struct SelfCollisionResult {
  bool collision = false;
  std::vector<std::pair<int, int>> colliding_pairs;  // link indices, a < b, in checking order
  std::vector<LinkContact> contacts;
  double min_distance = std::numeric_limits<double>::quiet_NaN();  // only when asked
  int closest_a = -1, closest_b = -1;
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  // witnesses in the root link's frame
  QueryStats stats;
};

}  // namespace bvh_collision
