// Inserting sensor scans into the octree with the semantics of octomap::OcTree::insertPointCloud.
//
// Scan points and the sensor origin are floats, as sensors deliver them and as OctoMap stores
// them; the ray arithmetic repeats OctoMap's, float for float, so both trees end with the same
// voxels and values.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

using ScanPoint = Eigen::Vector3f;

// The voxels a ray from `origin` to `end` crosses, without the end's voxel (OctoMap's 3-D DDA,
// computeRayKeys). False (and `keys` empty) when either end lies outside the key range.
bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys);

struct ScanOptions {
  double max_range = -1.0;  // < 0: unlimited; points beyond it clear along the ray only
};

struct ScanStats {
  std::size_t points = 0;           // points given
  std::size_t skipped_invalid = 0;  // NaN or Inf coordinates
  std::size_t skipped_outside = 0;  // outside the 16-bit key range
  std::size_t occupied = 0;         // voxels updated as occupied
  std::size_t free = 0;             // voxels updated as free
};

// One scan: every voxel crossed by a ray is updated once as free, every end point's voxel (within
// max_range) once as occupied, and a voxel that is an end point is not also freed.
ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const ScanPoint& origin,
                      const ScanOptions& options = {});

}  // namespace bvh_collision
