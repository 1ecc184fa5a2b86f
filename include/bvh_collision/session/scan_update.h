// A sensor's scan into the world, without ROS: the points (in the world frame) that lie on the
// robot (placed at the scan's time) or on a known object are taken out, the rest inserted into
// the store's octree with their rays from the sensor, and the new map's distance field built, so
// that the first query after it does not pay for it.
#pragma once

#include <cstddef>
#include <vector>

#include "bvh_collision/octree/scan.h"
#include "bvh_collision/session/robot_checkers.h"
#include "bvh_collision/world/environment_store.h"

namespace bvh_collision {

struct ScanUpdateOptions {
  double self_filter_padding = 0.02;  // points within this of the robot are not obstacles (m)
  double object_padding = 0.02;       // of a collision object or a carried one (m)
  ScanOptions scan;                   // range, workspace, limits, rays past the workspace
  bool distance_field = true;         // build the new map's distance field around the root
};

struct ScanUpdateResult {
  ScanStats stats;                 // the insertion's
  std::size_t on_robot = 0, shadowed = 0, on_objects = 0;  // the filters'
  bool field_made = false;          // a distance field was made for the new map
  OctreeDistanceField::UpdateWork field;  // how (Environment::octree_field_work)
};

// Inserts `points` seen from `origin` (all in the world frame) into the store's environment, the
// robot at `state` (model().variable_count() values) with its root at `root`. `no_return`: the
// far ends of rays that met nothing (a depth image's dark pixels): they clear up to the robot or
// an object where they pass through one, as a shadow does, and mark nothing. Throws as
// insert_scan and the filters do (a LimitExceeded past a limit), changing nothing then.
ScanUpdateResult update_scan(EnvironmentStore& store, const RobotCheckers& checkers, const std::vector<ScanPoint>& points,
                             const std::vector<ScanPoint>& no_return, const ScanPoint& origin, const double* state,
                             const Transform& root, const ScanUpdateOptions& options);

}  // namespace bvh_collision
