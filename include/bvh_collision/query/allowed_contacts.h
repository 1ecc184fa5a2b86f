// What the environment's checks skip, for a caller that asks to see it: the allowed (link,
// object) pairs that touch in a state (world/named_allowed_collisions.h).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/query/collision_checker.h"

namespace bvh_collision {

// The (link index, object name) pairs allowed to touch that do touch in `state` (exact, within
// the link's padding), each once, in link order; an object of several shapes named once ("id").
std::vector<std::pair<int, std::string>> allowed_object_contacts(const CollisionChecker& checker, const double* state,
                                                                 const Environment& env, const Transform& root_pose = {});

}  // namespace bvh_collision
