// The allowed (link, object) pairs that touch (query/allowed_contacts.h).
#include "bvh_collision/query/allowed_contacts.h"

#include <algorithm>

namespace bvh_collision {

// Per link, the objects it may touch in an environment of their own (with no allowances), that
// link alone checked against them for every contact.
std::vector<std::pair<int, std::string>> allowed_object_contacts(const CollisionChecker& checker, const double* state,
                                                                 const Environment& env, const Transform& root_pose) {
  std::vector<std::pair<int, std::string>> out;
  if (env.allowed_collisions().empty()) return out;
  const auto& links = checker.model().links();
  for (std::size_t l = 0; l < links.size(); ++l) {
    if (checker.collision_model().shapes()[l].empty()) continue;  // (a carried object has shapes, no URDF elements)
    Environment allowed(env.octree().resolution());
    for (std::size_t o = 0; o < env.objects().size(); ++o) {
      if (env.object_allowed(links[l].name, o)) allowed.add_object(env.objects()[o]);
    }
    if (allowed.objects().empty()) continue;
    std::vector<char> only(links.size(), 0);
    only[l] = 1;
    EnvironmentRequest request;
    request.all_links = true;
    request.octree = false;
    request.root_pose = root_pose;
    request.only_links = &only;
    for (const EnvironmentContact& c : checker.check_environment(state, allowed, request).contacts) {
      const std::pair<int, std::string> pair{static_cast<int>(l), object_name(c.object)};
      if (std::find(out.begin(), out.end(), pair) == out.end()) out.push_back(pair);
    }
  }
  return out;
}

}  // namespace bvh_collision
