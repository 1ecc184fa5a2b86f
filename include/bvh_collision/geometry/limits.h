// Bounds on the work one request, one cloud or one robot may ask for (in the geometry
// layer so that every layer can check its own: the octree its scans, the checker its robot and
// queries, the node its messages and parameters): a motion checked
// at 1e-9 rad over 3 rad once kept the node busy for ten minutes. Each limit exceeded is a
// LimitExceeded error that names the limit, the amount asked for and the node parameter that
// raises it; nothing is changed by the request that exceeds it.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace bvh_collision {

struct Limits {
  std::size_t motion_states = 100000;       // ~max_motion_states: states of one fixed-step motion
  std::size_t batch_states = 1000000;       // ~max_batch_states: configurations of one batch
  std::size_t cloud_points = 5000000;       // ~max_cloud_points: points of one cloud
  std::size_t ray_voxels = 10000;           // ~max_ray_voxels: voxels one ray may cross (max_range / resolution)
  std::size_t object_triangles = 2000000;   // ~max_object_triangles: triangles of one collision object
  std::size_t robot_links = 10000;          // ~max_robot_links: links of the robot
  std::size_t checked_pairs = 1000000;      // ~max_checked_pairs: self pairs a check examines
};

class LimitExceeded : public std::invalid_argument {
 public:
  // "<what> needs <asked>, more than the limit of <limit> (parameter ~<parameter> raises it)".
  LimitExceeded(const std::string& what, double asked, std::size_t limit, const std::string& parameter);
};

// Throws LimitExceeded when `asked` (possibly not finite: then it is always too many) exceeds
// `limit`.
void check_limit(const std::string& what, double asked, std::size_t limit, const std::string& parameter);

}  // namespace bvh_collision
