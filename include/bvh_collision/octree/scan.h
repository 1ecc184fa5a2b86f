// Inserting sensor scans into the octree with the semantics of octomap::OcTree::insertPointCloud.
//
// Scan points and the sensor origin are floats, as sensors deliver them and as OctoMap stores
// them; the ray arithmetic repeats OctoMap's, float for float, so both trees end with the same
// voxels and values.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "bvh_collision/geometry/limits.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

using ScanPoint = Eigen::Vector3f;

// The voxels a ray from `origin` to `end` crosses, without the end's voxel (OctoMap's 3-D DDA,
// computeRayKeys). False (and `keys` empty) when either end lies outside the key range.
bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys);

// OctoMap's bounding-box limit: end points outside the box are dropped (with their rays), and a
// kept point's ray updates only the voxels inside the box. Compared in float, as OctoMap does.
struct ScanWorkspace {
  ScanPoint min;
  ScanPoint max;
  bool contains(const ScanPoint& p) const { return (p.array() >= min.array()).all() && (p.array() <= max.array()).all(); }
};

struct ScanOptions {
  double max_range = -1.0;                 // < 0: unlimited; points beyond it clear along the ray only
  std::optional<ScanWorkspace> workspace;  // "model only what a scene needs"
  int threads = 0;                         // rays are cast on this many threads; 0: one per core
  // Points per scan (end points and clear-only ones together) and voxels per ray (max_range /
  // resolution, when max_range is given; without it a ray stays inside the 16-bit key range):
  // insert_scan throws LimitExceeded beyond them, before it changes anything.
  Limits limits;
};

struct ScanStats {
  std::size_t points = 0;             // points given
  std::size_t skipped_invalid = 0;    // NaN or Inf coordinates
  std::size_t skipped_outside = 0;    // outside the 16-bit key range
  std::size_t skipped_workspace = 0;  // outside the workspace box (or beyond max_range with one)
  std::size_t occupied = 0;           // voxels updated as occupied
  std::size_t free = 0;               // voxels updated as free
};

// One scan, as octomap::OcTree::insertPointCloud (with setBBXMin/Max and useBBXLimit when a
// workspace is given): every voxel a ray crosses is updated once as free, every end point's voxel
// (within max_range) once as occupied, and a voxel that is an end point is not also freed.
ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const ScanPoint& origin,
                      const ScanOptions& options = {});

// The same with rays that only clear: `clear_only` end points mark nothing occupied, their rays
// free the voxels they cross (without the end's voxel), as a point beyond max_range does. The self
// filter sends the robot's own points and their shadows this way, shortened to before the robot.
// ScanStats::points counts both lists.
ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const std::vector<ScanPoint>& clear_only,
                      const ScanPoint& origin, const ScanOptions& options = {});

// End points only, without rays (no free space observed): each voxel holding a point is updated
// once as occupied. max_range does not apply (there is no sensor origin); the workspace does.
ScanStats insert_points(Octree& tree, const std::vector<ScanPoint>& points, const ScanOptions& options = {});

}  // namespace bvh_collision
