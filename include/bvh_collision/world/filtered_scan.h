// The self filter's split of a scan (CollisionChecker::filter_scan): the result.
#pragma once

#include <cstddef>
#include <vector>

#include "bvh_collision/octree/scan.h"

namespace bvh_collision {

// A scan split by the self filter, ready for insert_scan(tree, obstacles, clear_only, sensor).
struct FilteredScan {
  std::vector<ScanPoint> obstacles;   // kept, in scan order (invalid points too: insert_scan counts them)
  std::vector<ScanPoint> clear_only;  // robot and object points and shadows, cut to before what they met
  std::size_t on_robot = 0;           // points on or within padding of a link, or inside a closed one
  std::size_t shadowed = 0;           // points whose ray from the sensor passes through a link
  std::size_t on_objects = 0;         // points on or within padding of a collision object (filter_objects)
};

}  // namespace bvh_collision
