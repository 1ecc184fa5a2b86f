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

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "bvh_collision/geometry/types.h"
#include "bvh_collision/octree/octree.h"
#include "bvh_collision/octree/versioned_grid.h"

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

  // The field of `tree` when this one is the field of a tree that differs from it only in the
  // occupancy of the voxels `flipped` (Octree::update_sorted's, ScanStats::flipped; duplicates and
  // voxels outside the grid allowed): the same box and cap, every value equal to a build's. Only
  // the blocks of 16^3 voxels that a flipped voxel can reach (within the cap's squared distance,
  // past which every value reads as the cap) are recomputed, each from the occupancy of a window
  // reaching that far around it: the work grows with the change, not with the map, until those
  // blocks are an eighth of the grid, where a build costs less and is done instead
  // (docs/performance.md, "A live world"). The counts of the work into `work` when given.
  //
  // Made in place: the cells live in a VersionedGrid (octree/versioned_grid.h), and when this field
  // is its latest version the new values are written over its file, this field (and every other
  // earlier version still held) first keeping each page about to change. So this field reads as
  // before, and holds memory of its own only for the pages changed since (a pinned world's field).
  // When a newer field was already made from this one, the cells are copied instead.
  struct UpdateWork {
    std::size_t flipped = 0;        // flipped voxels inside the grid
    std::size_t blocks = 0;         // blocks recomputed
    std::size_t cells = 0;          // their cells (computed)
    std::size_t window_cells = 0;   // cells read: the blocks' windows
    std::size_t changed_cells = 0;  // cells whose value changed (written)
    std::size_t kept_pages = 0;     // pages copied into earlier versions still held, before being written
    std::size_t copied_cells = 0;   // cells copied into a grid of its own (not made in place)
    bool rebuilt = false;           // the blocks were more than an eighth of the grid: built anew
  };
  OctreeDistanceField updated(const Octree& tree, const std::vector<OctreeKey>& flipped, UpdateWork* work = nullptr) const;
  // The same over the lists of several changes in a row (their union: each voxel takes the
  // occupancy `tree` gives it). With `in_place` false, always into a grid of its own (a copy).
  OctreeDistanceField updated(const Octree& tree, const std::vector<const std::vector<OctreeKey>*>& flipped,
                              UpdateWork* work = nullptr, bool in_place = true) const;

  // The same, in place: this field becomes the field of `tree`, its cells written over with no new
  // version, when it is its grid's latest version and nothing else holds its cells (no reader can
  // see the writes; the other versions alive keep their pages); otherwise as updated(). An
  // environment makes a field nobody holds any more the next one this way (no page kept, no
  // mapping made: Environment::octree_distance_field).
  void follow(const Octree& tree, const std::vector<const std::vector<OctreeKey>*>& flipped, UpdateWork* work = nullptr);

  // Equal grids and bounds (a test's comparison of an updated field with a build).
  bool same_values(const OctreeDistanceField& other) const;

  // Are both fields versions of one grid (one made from the other in place)?
  bool same_grid(const OctreeDistanceField& other) const {
    return version_ && other.version_ && version_->grid() == other.version_->grid();
  }
  double cap() const { return cap_; }
  std::size_t cells() const { return cells_; }
  // Memory this field holds: its grid's file and the pages of it kept for this version alone.
  std::size_t memory_bytes() const;
  // The same for several fields together, each grid counted once (fields made from one another
  // share their grid's pages but the ones each kept).
  static std::size_t distinct_memory_bytes(const std::vector<const OctreeDistanceField*>& fields);

 private:
  double resolution_ = 0.0, inverse_ = 0.0, cap_ = 0.0;
  std::vector<double> bound_of_squared_;  // the bound for each D whose bound is below the cap
  std::int64_t inner_lo_[3] = {0, 0, 0}, inner_hi_[3] = {-1, -1, -1};  // the box's voxels
  std::int64_t grid_lo_[3] = {0, 0, 0}, size_[3] = {0, 0, 0};          // the box and the cap
  // per grid voxel, D, at most the first D whose bound is the cap (bound_of_squared_.size() - 1):
  // every larger one reads as the cap, and an update recomputes only what the cap can reach
  std::shared_ptr<const GridVersion> version_;  // shared by copies of this field: it never changes
  const std::uint32_t* squared_ = nullptr;      // version_'s cells
  std::size_t cells_ = 0;
  void adopt(const std::shared_ptr<VersionedGrid>& grid);
  std::int64_t index(std::int64_t x, std::int64_t y, std::int64_t z) const { return (x * size_[1] + y) * size_[2] + z; }
  void recompute_block(const std::int64_t lo[3], const std::int64_t hi[3], std::int64_t reach, VersionedGrid& grid,
                       UpdateWork& work) const;
  // An update's parts: the blocks a change reaches, whether a build is cheaper, the build, the blocks.
  struct Change;
  Change change_of(const std::vector<const std::vector<OctreeKey>*>& flipped) const;
  bool build_is_cheaper(const Change& change) const;
  OctreeDistanceField rebuilt(const Octree& tree, std::size_t flipped, UpdateWork* work) const;
  void apply(const Octree& tree, const Change& change, VersionedGrid& grid, UpdateWork& work) const;
  // how far (in voxels) a changed voxel's effect reaches: past it every value reads as the cap
  std::int64_t reach() const {
    return static_cast<std::int64_t>(std::ceil(std::sqrt(double(bound_of_squared_.size() - 1))));
  }
};

}  // namespace bvh_collision
