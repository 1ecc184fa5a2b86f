// Inserting sensor scans into the octree with the semantics of octomap::OcTree::insertPointCloud.
//
// Scan points and the sensor origin are floats, as sensors deliver them and as OctoMap stores
// them; the ray arithmetic repeats OctoMap's, float for float, so both trees end with the same
// voxels and values.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "bvh_collision/geometry/limits.h"
#include "bvh_collision/geometry/simd_path.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

using ScanPoint = Eigen::Vector3f;

// The voxels a ray from `origin` to `end` crosses, without the end's voxel (OctoMap's 3-D DDA,
// computeRayKeys). False (and `keys` empty) when either end lies outside the key range. `path`:
// the walk's build (both take the same steps; tests compare them).
bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys,
              SimdPath path = SimdPath::kAuto);

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
  // With a workspace, OctoMap drops a ray whose end is outside it or beyond max_range, so a wall
  // past the workspace clears nothing in it. True: such a ray, and every clear-only ray, frees the
  // voxels it crosses inside the workspace (up to max_range); an end point inside the box and
  // within range is inserted as before. False: OctoMap's bounding-box rule, tree for tree.
  bool clip_rays_to_workspace = false;
  // Memory for the crossed voxels: each thread marks those in the box of the sensor and the end
  // points (within the workspace) in a bitmap of that box, one bit a voxel, when it holds at most
  // this many voxels (the default, 2^26, is 8 MB), else in a bitmap of the cube of this many voxels
  // about the sensor; the others in a hash set of 8 x 8 x 8 blocks. The tree is the same either
  // way; 0 takes the set for all.
  std::uint64_t max_dense_voxels = std::uint64_t{1} << 26;
  // The rays' walk: built for plain x86-64 and for AVX2, the CPU's best taken by default (the
  // same voxels either way; tests and benchmarks name one). kAvx2 on a CPU without AVX2 throws
  // std::runtime_error before anything changes.
  SimdPath simd = SimdPath::kAuto;
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
  bool bitmap = false;                // crossed voxels marked in a bitmap of the scan's box (max_dense_voxels)
  // The voxels whose occupancy the scan changed (free or unknown to occupied, or back), each once:
  // what a kept distance field follows (OctreeDistanceField::updated).
  std::vector<OctreeKey> flipped;
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

// A depth camera's pinhole model (sensor_msgs/CameraInfo's K): pixel (u, v) looks along
// ((u - cx) / fx, (v - cy) / fy, 1) in the camera's optical frame (z forward, x right, y down).
struct PinholeCamera {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  bool valid() const;  // finite, fx and fy non-zero
};

// The pinhole model an organized scan (row-major, `width` x `height`, in its optical frame) was
// made with, fitted to its valid points (a depth image's cloud: x / z and y / z are linear in the
// pixel's column and row). Nullopt when fewer than two columns or rows hold a point in front of
// the camera, or when some point is off the fitted ray of its pixel by more than 1e-3 of its
// depth (not a pinhole camera's cloud: a LiDAR's rings, say).
std::optional<PinholeCamera> fit_pinhole(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height);

// Does the camera agree with the organized scan: every point that returned (finite, not the zero
// point some drivers write for none) in front of it and on its pixel's ray within 1e-3 of its
// depth? A camera given by configuration that does not is not this cloud's: its rays would clear
// the wrong space. True for a scan with no point that returned (nothing to contradict it).
bool pinhole_agrees(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height,
                    const PinholeCamera& camera);

// Rays that returned nothing: for each pixel of an organized scan whose point is NaN or infinite,
// the point `range` along the pixel's ray from the camera (optical frame), for insert_scan's
// clear-only list (a pixel whose ray has no finite direction, under an absurd camera, none). Throws std::invalid_argument when the size is not width x height, the camera
// is not valid or the range is not positive and finite.
std::vector<ScanPoint> no_return_ends(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height,
                                      const PinholeCamera& camera, double range);

// End points only, without rays (no free space observed): each voxel holding a point is updated
// once as occupied. max_range does not apply (there is no sensor origin); the workspace does.
ScanStats insert_points(Octree& tree, const std::vector<ScanPoint>& points, const ScanOptions& options = {});

}  // namespace bvh_collision
