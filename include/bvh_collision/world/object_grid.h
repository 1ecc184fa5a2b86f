// The collision objects of one environment snapshot as sphere queries see them (the planner's
// state and motion checks, query/scene_checker.h): each object's exact primitive in its own
// frame, and a grid over the robot's reach whose cells list the objects near them.
#pragma once

#include <cstdint>
#include <vector>

#include "bvh_collision/world/environment.h"
#include "bvh_collision/geometry/primitives.h"
#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// The collision objects of a snapshot, for sphere queries: each object's exact primitive in its
// own frame (boxes included; meshes by their bounding sphere until the exact test), and a grid over
// a box of the world whose cells list the objects within `reach` of them.
class ObjectGrid {
 public:
  ObjectGrid() = default;
  ObjectGrid(const ObjectList& objects, const Vec3& lo, const Vec3& hi, double reach, double cell);

  // Calls f(object index) for every object that might lie within `radius` of `centre`: those
  // of the cell's list not proven farther (when radius <= reach and the centre lies in the
  // grid), else every object.
  template <class F>
  void for_each_near(const Vec3& centre, double radius, F&& f) const {
    const int c = radius <= reach_ ? cell_of(centre) : -1;
    if (c < 0) {
      for (std::size_t o = 0; o < solids_.size(); ++o) f(static_cast<int>(o));
      return;
    }
    if (radius < clear_[c]) return;
    for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
      if (radius >= apart_[k]) f(static_cast<int>(list_[k]));
    }
  }

  // Is every object proven farther than `radius` from `centre` by the centre's cell (for_each_near
  // would offer none)? False when it cannot tell.
  bool clear(const Vec3& centre, double radius) const {
    if (solids_.empty()) return true;
    const int c = radius <= reach_ ? cell_of(centre) : -1;
    return c >= 0 && radius < clear_[c];
  }

  // Does the ball meet object `o`? True whenever it does (rounding margins included); for a mesh
  // object, whenever the ball meets its bounding sphere.
  bool ball_meets(int o, const Vec3& centre, double radius) const;
  // A lower bound on how deep `centre` lies inside object `o` (the radius of a ball around it
  // inside the object; <= 0 outside); -infinity for a mesh object or a cone (no bound given).
  double depth(int o, const Vec3& centre) const;
  // Is the ball's test against object `o` exact (a primitive), or only its bounding sphere's?
  bool exact_ball_test(int o) const { return solids_[o].primitive; }

  // The same tests in the frame of a primitive object (exact_ball_test(o)), for a walk that
  // carries its balls there at once (one transform a ball, not two): `to_local(o) * pose` places
  // them, and `margin` is the rounding of the world centres they stand for (the pose's margin;
  // the object's own is added here). True whenever the ball meets the primitive.
  const Transform& to_local(int o) const { return solids_[o].to_local; }
  bool local_ball_meets(int o, const Vec3& p, double radius, double margin) const;
  // A lower bound on how deep the local point lies inside the primitive (<= 0 outside).
  double local_depth(int o, const Vec3& p, double margin) const;
  std::size_t size() const { return solids_.size(); }
  std::size_t cells() const { return start_.empty() ? 0 : start_.size() - 1; }

 private:
  struct Solid {
    Transform to_local;  // world -> object frame
    Primitive shape;     // exact when `primitive`
    Vec3 half = Vec3::Zero();  // its box's half extents (own frame)
    bool primitive = false;
    Vec3 centre = Vec3::Zero();  // world bounding sphere
    double radius = 0.0;
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // world box
    double margin = 0.0;  // rounding of the ball test at this object's scale
  };
  // (In the header: a planner's state asks it once a link.)
  int cell_of(const Vec3& p) const {
    // (By the inverse, not divided: a point that rounding puts one cell over lies within
    // rounding of that cell, and the lists and bounds are built with margins far above that.
    // The three axes written out: GCC keeps a loop over them.)
    const double x = (p[0] - origin_[0]) * inverse_cell_, y = (p[1] - origin_[1]) * inverse_cell_,
                 z = (p[2] - origin_[2]) * inverse_cell_;
    const bool inside = (x >= 0.0) & (x < extent_[0]) & (y >= 0.0) & (y < extent_[1]) & (z >= 0.0) & (z < extent_[2]);
    if (!inside) return -1;  // outside (or not a number): every object
    return (static_cast<int>(z) * n_[1] + static_cast<int>(y)) * n_[0] + static_cast<int>(x);
  }
  void cell_bounds(double half_diagonal);

  std::vector<Solid> solids_;
  Vec3 origin_ = Vec3::Zero();
  double cell_ = 1.0, inverse_cell_ = 1.0, reach_ = 0.0;
  int n_[3] = {0, 0, 0};
  double extent_[3] = {0.0, 0.0, 0.0};  // n_ as doubles
  std::vector<std::uint32_t> start_, list_;
  // Per list entry, a lower bound on the distance from any point of the cell to the object
  // (rounding taken off); per cell, the least of its entries' (infinity for none).
  std::vector<double> apart_, clear_;
};

}  // namespace bvh_collision
