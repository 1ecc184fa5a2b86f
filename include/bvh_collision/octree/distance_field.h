// Lower bounds on the distance to the octree's occupied cubes over a box, from one exact squared
// Euclidean distance transform of its voxels (the step toward answering "is this
// sphere clear of every obstacle?" with one lookup: check_environment, check_batch and certified
// motions use it through Environment::octree_distance_field).
//
// Why the bound holds. Voxel i is the cube [i res, (i + 1) res] per axis (octree_key.h). For every
// voxel X of the grid the transform gives D(X), the smallest squared distance, in voxels, between
// X's centre and the centre of an occupied voxel of the grid; it is exact (integer arithmetic,
// the lower envelope of parabolas of Felzenszwalb and Huttenlocher with exact comparisons). A
// point p of X and a point q of an occupied voxel O are at least |cX - cO| - |p - cX| - |q - cO|
// >= (sqrt(D) - sqrt(3)) res apart. The grid reaches `cap` (rounded up to voxels, plus one) beyond
// the box, so an occupied voxel outside it is at least cap from any point of the box. Hence, for p
// in the box, min((sqrt(D(X)) - sqrt(3)) res, cap) is a lower bound on the distance from p to
// every occupied cube; a safety margin (geometry/safety_margin.h) covers the rounding of p / res
// and of the square root. It is at most 2 sqrt(3) res below the true distance (when under cap).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "bvh_collision/geometry/types.h"
#include "bvh_collision/octree/octree.h"

namespace bvh_collision {

class OctreeDistanceField {
 public:
  OctreeDistanceField() = default;
  // The field over the voxels whose cubes meet [lo, hi], knowing the occupied voxels up to `cap`
  // beyond it. Throws std::invalid_argument for a box that is not finite or empty, a cap that is
  // not a positive finite number, or more than `max_cells` grid cells (the box plus the cap).
  static OctreeDistanceField build(const Octree& tree, const Vec3& lo, const Vec3& hi, double cap,
                                   std::size_t max_cells = std::size_t(1) << 26);

  // A lower bound on the distance from p to every occupied cube of the tree, at most cap(); 0 for
  // a point outside the box (or not finite): nothing is known there.
  double lower_bound(const Vec3& p) const;

  // Does the closed ball meet an occupied voxel? Answered from the grid's own record of which
  // voxels are occupied (squared distance 0), exactly up to rounding on the side of yes: true
  // whenever it meets one. Empty when the ball's voxels are not all in the grid.
  std::optional<bool> ball_meets_occupied(const Vec3& centre, double radius) const;

  double cap() const { return cap_; }
  std::size_t cells() const { return squared_.size(); }
  std::size_t memory_bytes() const { return squared_.capacity() * sizeof(std::uint32_t); }

 private:
  double resolution_ = 0.0, inverse_ = 0.0, cap_ = 0.0;
  std::vector<double> bound_of_squared_;  // the bound for each D whose bound is below the cap
  std::int64_t inner_lo_[3] = {0, 0, 0}, inner_hi_[3] = {-1, -1, -1};  // the box's voxels
  std::int64_t grid_lo_[3] = {0, 0, 0}, size_[3] = {0, 0, 0};          // the box and the cap
  std::vector<std::uint32_t> squared_;  // per grid voxel, D (kFar: no occupied voxel in the grid)
};

}  // namespace bvh_collision
