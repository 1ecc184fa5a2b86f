// ObjectGrid: the objects of a snapshot for sphere queries (world/object_grid.h).
#include "bvh_collision/world/object_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {

namespace {

// The world box of a primitive or mesh bound at `pose`: |R| half-extents around the centre.
void world_box(const Transform& pose, const Vec3& centre, const Vec3& half, Vec3& lo, Vec3& hi) {
  const Vec3 c = pose * centre;
  const Vec3 e = pose.R.cwiseAbs() * half;
  const double m = pose_margin(c.norm() + half.norm());
  lo = c - e - Vec3::Constant(m);
  hi = c + e + Vec3::Constant(m);
}

// The squared distance from p to the box [lo, hi].
double squared_box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.cwiseMax(lo).cwiseMin(hi) - p).squaredNorm();
}

// The cell (0 to n - 1) a coordinate in cells falls in, clamped as a double: a box wider than an
// int counts (or not a number) has no int to clamp. (NaN: the first cell for a box's low side,
// the last for its high side, so the box spans them all.)
int first_cell(double x, int n) { return x > 0.0 ? static_cast<int>(std::min(std::floor(x), n - 1.0)) : 0; }
int last_cell(double x, int n) { return x < n - 1.0 ? static_cast<int>(std::max(std::floor(x), 0.0)) : n - 1; }

}  // namespace

ObjectGrid::ObjectGrid(const ObjectList& objects, const Vec3& lo, const Vec3& hi, double reach,
                       double cell)
    : origin_(lo), cell_(cell), inverse_cell_(1.0 / cell), reach_(reach) {
  for (const CollisionObject& o : objects) {
    Solid s;
    s.to_local = o.pose.inverse();
    const ShapeRef exact = exact_shape_of(o);
    s.primitive = exact_primitive(exact) != nullptr;
    s.shape = exact.primitive;
    if (s.primitive) s.half = half_extents(s.shape);
    s.centre = o.pose * o.bound_center;
    s.radius = o.bound_radius;
    world_box(o.pose, s.primitive ? Vec3::Zero() : o.bound_center,
              s.primitive ? half_extents(s.shape) : Vec3::Constant(o.bound_radius), s.lo, s.hi);
    s.margin = pose_margin(s.centre.norm() + s.radius);
    solids_.push_back(s);
  }
  for (int i = 0; i < 3; ++i) {
    n_[i] = std::max(1, static_cast<int>(std::ceil((hi[i] - lo[i]) / cell)));
    extent_[i] = n_[i];
  }
  const std::size_t cells = static_cast<std::size_t>(n_[0]) * n_[1] * n_[2];
  start_.assign(cells + 1, 0);
  // A cell lists an object when the object's box comes within reach of the cell's box (the ball
  // of a query centred in the cell, of radius up to reach, can then meet it). The lists are
  // counted first and then written into one array, in object order within a cell: a list per cell
  // cost an allocation for each of a scene's thousands of cells that any object came near.
  const double half_diagonal = 0.5 * std::sqrt(3.0) * cell;
  auto for_each_cell_near = [&](const Solid& s, auto&& f) {
    int first[3], last[3];
    for (int i = 0; i < 3; ++i) {
      first[i] = first_cell((s.lo[i] - reach - lo[i]) / cell, n_[i]);
      last[i] = last_cell((s.hi[i] + reach - lo[i]) / cell, n_[i]);
    }
    for (int z = first[2]; z <= last[2]; ++z) {
      for (int y = first[1]; y <= last[1]; ++y) {
        for (int x = first[0]; x <= last[0]; ++x) {
          const Vec3 centre = lo + cell * Vec3(x + 0.5, y + 0.5, z + 0.5);
          const double within = reach + half_diagonal;
          if (squared_box_distance(centre, s.lo, s.hi) > within * within * (1 + 1e-9)) continue;
          f((static_cast<std::size_t>(z) * n_[1] + y) * n_[0] + x);
        }
      }
    }
  };
  for (const Solid& s : solids_) for_each_cell_near(s, [&](std::size_t c) { ++start_[c + 1]; });
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  list_.resize(start_.back());
  std::vector<std::uint32_t> next(start_.begin(), start_.end() - 1);
  for (std::size_t o = 0; o < solids_.size(); ++o) {
    for_each_cell_near(solids_[o], [&](std::size_t c) { list_[next[c]++] = static_cast<std::uint32_t>(o); });
  }
  cell_bounds(half_diagonal);
}

// A ball centred in a cell and smaller than the cell's distance to an object, less the cell's
// half diagonal, cannot meet the object: most link balls of a planner's state are such, and
// pass with no object test. The distance from the cell's centre is the primitive's own, or for
// a mesh object the larger of its box's and its bounding sphere's; the margin covers its
// rounding at this scale twice over.
void ObjectGrid::cell_bounds(double half_diagonal) {
  apart_.resize(list_.size());
  clear_.assign(start_.size() - 1, std::numeric_limits<double>::infinity());
  for (std::size_t c = 0; c + 1 < start_.size(); ++c) {
    const int x = static_cast<int>(c % n_[0]), y = static_cast<int>(c / n_[0] % n_[1]), z = static_cast<int>(c / n_[0] / n_[1]);
    const Vec3 centre = origin_ + cell_ * Vec3(x + 0.5, y + 0.5, z + 0.5);
    for (std::uint32_t k = start_[c]; k < start_[c + 1]; ++k) {
      const Solid& s = solids_[list_[k]];
      double d = std::sqrt(squared_box_distance(centre, s.lo, s.hi));
      if (s.primitive) {
        const Vec3 p = s.to_local * centre;
        d = std::max(d, (closest_point(s.shape, p) - p).norm());
      } else {
        d = std::max(d, (centre - s.centre).norm() - s.radius);
      }
      const double margin = 2.0 * (s.margin + pose_margin(centre.cwiseAbs().sum() + 3.0 * cell_ + d));
      apart_[k] = d - half_diagonal - margin;
      clear_[c] = std::min(clear_[c], apart_[k]);
    }
  }
}

double ObjectGrid::depth(int o, const Vec3& centre) const {
  const Solid& s = solids_[o];
  if (!s.primitive) return -std::numeric_limits<double>::infinity();
  // Less the rounding of the transform and of the depth at this scale.
  return inscribed_depth(s.shape, s.to_local * centre) - 2.0 * (s.margin + pose_margin(centre.norm()));
}

// (Less a margin twice that of the world tests: the composed transform rounds at the scale of
// both the object's and the pose's coordinates, far below either margin.)
bool ObjectGrid::local_ball_meets(int o, const Vec3& p, double radius, double margin) const {
  const Solid& s = solids_[o];
  const double reach = radius + 2.0 * (s.margin + margin) + pose_margin(p.cwiseAbs().sum());
  if ((p.cwiseAbs() - s.half).cwiseMax(0.0).squaredNorm() > reach * reach) return false;  // the primitive's box
  return (closest_point(s.shape, p) - p).squaredNorm() <= reach * reach;
}

double ObjectGrid::local_depth(int o, const Vec3& p, double margin) const {
  const Solid& s = solids_[o];
  return inscribed_depth(s.shape, p) - 2.0 * (s.margin + margin + pose_margin(p.norm()));
}

bool ObjectGrid::ball_meets(int o, const Vec3& centre, double radius) const {
  const Solid& s = solids_[o];
  // The margin from |centre|'s upper bound |x| + |y| + |z|: no square root in a test a sphere
  // walk makes thousands of times a motion (a margin up to sqrt(3) larger only widens the test).
  const double reach = radius + s.margin + pose_margin(centre.cwiseAbs().sum());
  if (squared_box_distance(centre, s.lo, s.hi) > reach * reach) return false;
  if (!s.primitive) return (centre - s.centre).squaredNorm() <= (reach + s.radius) * (reach + s.radius);
  const Vec3 p = s.to_local * centre;
  return (closest_point(s.shape, p) - p).squaredNorm() <= reach * reach;
}

}  // namespace bvh_collision
