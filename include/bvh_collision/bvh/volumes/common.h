// What every bounding volume shares: the relative frame and ray the tests take, the box
// separating-axis routines several types reduce to, and the declarations each type specialises.
// The margins are geometry/safety_margin.h's policy.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// The volume tests sit in the innermost traversal loops; GCC's -O2 inliner otherwise keeps some
// of them out of line.
#define BVH_HOT [[gnu::always_inline]] inline

namespace detail {
// c = a^T * b for 3x3 matrices, and a^T * v, written out.
BVH_HOT Mat3 transpose_times(const Mat3& a, const Mat3& b) {
  Mat3 c;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c(i, j) = a(0, i) * b(0, j) + a(1, i) * b(1, j) + a(2, i) * b(2, j);
  }
  return c;
}
BVH_HOT Mat3 times(const Mat3& a, const Mat3& b) {
  Mat3 c;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) c(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
  }
  return c;
}
BVH_HOT Vec3 transpose_times(const Mat3& a, const Vec3& v) {
  return {a(0, 0) * v[0] + a(1, 0) * v[1] + a(2, 0) * v[2], a(0, 1) * v[0] + a(1, 1) * v[1] + a(2, 1) * v[2],
          a(0, 2) * v[0] + a(1, 2) * v[1] + a(2, 2) * v[2]};
}
BVH_HOT Vec3 times(const Mat3& a, const Vec3& v) {
  return {a(0, 0) * v[0] + a(0, 1) * v[1] + a(0, 2) * v[2], a(1, 0) * v[0] + a(1, 1) * v[1] + a(1, 2) * v[2],
          a(2, 0) * v[0] + a(2, 1) * v[1] + a(2, 2) * v[2]};
}
BVH_HOT Mat3 abs_plus_epsilon(const Mat3& m) {
  Mat3 r;
  for (int k = 0; k < 9; ++k) r.data()[k] = std::abs(m.data()[k]) + kAxisEpsilon;
  return r;
}

}  // namespace detail

// The pose of mesh b in mesh a's frame, with what the volume tests need precomputed.
struct RelativeFrame {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  Mat3 abs_R = Mat3::Identity();  // |R| plus a small epsilon: robust for near-parallel axes
  bool pure_translation = true;

  static RelativeFrame from(const Transform& b_in_a) {
    RelativeFrame f;
    f.R = b_in_a.R;
    f.t = b_in_a.t;
    f.abs_R = detail::abs_plus_epsilon(b_in_a.R);
    f.pure_translation = b_in_a.R == Mat3::Identity();
    if (f.pure_translation) f.abs_R = Mat3::Identity();
    return f;
  }
  Vec3 apply(const Vec3& p) const { return detail::times(R, p) + t; }
};

// A ray for conservative volume tests: origin, direction, and precomputed inverse direction.
struct Ray {
  Vec3 origin;
  Vec3 direction;  // need not be unit
  Vec3 inv_direction;
  double max_t;    // the ray is origin + s * direction, s in [0, max_t]

  Ray(const Vec3& o, const Vec3& d, double max) : origin(o), direction(d), max_t(max) {
    for (int i = 0; i < 3; ++i) inv_direction[i] = 1.0 / d[i];
  }
};

// ------------------------------------------------------------------------------ shared helpers

namespace detail {

// Separating-axis test for two boxes in a's box frame: a is axis-aligned with half extents ha
// centred at the origin; b has axes B (columns; abs_B = |B| + epsilon) and half extents hb at
// centre T. Returns false only when some axis separates them by more than `padding`.
// Written out in scalars: at -O2 the compiler does not inline Eigen's small products here.
BVH_HOT bool boxes_overlap(const Vec3& T, const Vec3& ha, const Mat3& B, const Mat3& abs_B, const Vec3& hb,
                           double padding) {
  const double scale = ha[0] + ha[1] + ha[2] + hb[0] + hb[1] + hb[2] + std::abs(T[0]) + std::abs(T[1]) + std::abs(T[2]);
  const double s = padding + kVolumeMargin * scale;
  // a's face axes
  if (std::abs(T[0]) > ha[0] + abs_B(0, 0) * hb[0] + abs_B(0, 1) * hb[1] + abs_B(0, 2) * hb[2] + s) return false;
  if (std::abs(T[1]) > ha[1] + abs_B(1, 0) * hb[0] + abs_B(1, 1) * hb[1] + abs_B(1, 2) * hb[2] + s) return false;
  if (std::abs(T[2]) > ha[2] + abs_B(2, 0) * hb[0] + abs_B(2, 1) * hb[1] + abs_B(2, 2) * hb[2] + s) return false;
  // b's face axes
  for (int j = 0; j < 3; ++j) {
    const double ra = ha[0] * abs_B(0, j) + ha[1] * abs_B(1, j) + ha[2] * abs_B(2, j);
    if (std::abs(T[0] * B(0, j) + T[1] * B(1, j) + T[2] * B(2, j)) > ra + hb[j] + s) return false;
  }
  // a_i x b_j, written out (i1, i2 and j1, j2 are the other two indices, cyclically)
#define BVH_CROSS_AXIS(i, i1, i2, j, j1, j2)                                                         \
  if (std::abs(T[i2] * B(i1, j) - T[i1] * B(i2, j)) >                                               \
      ha[i1] * abs_B(i2, j) + ha[i2] * abs_B(i1, j) + hb[j1] * abs_B(i, j2) + hb[j2] * abs_B(i, j1) + s) \
    return false;
  BVH_CROSS_AXIS(0, 1, 2, 0, 1, 2)
  BVH_CROSS_AXIS(0, 1, 2, 1, 2, 0)
  BVH_CROSS_AXIS(0, 1, 2, 2, 0, 1)
  BVH_CROSS_AXIS(1, 2, 0, 0, 1, 2)
  BVH_CROSS_AXIS(1, 2, 0, 1, 2, 0)
  BVH_CROSS_AXIS(1, 2, 0, 2, 0, 1)
  BVH_CROSS_AXIS(2, 0, 1, 0, 1, 2)
  BVH_CROSS_AXIS(2, 0, 1, 1, 2, 0)
  BVH_CROSS_AXIS(2, 0, 1, 2, 0, 1)
#undef BVH_CROSS_AXIS
  return true;
}

// A lower bound on the distance between the two boxes (same frame convention): the largest gap
// along the 15 separating axes (cross axes normalised) or between circumscribed spheres.
inline double boxes_distance_lower_bound(const Vec3& T, const Vec3& ha, const Mat3& B, const Mat3& abs_B,
                                         const Vec3& hb) {
  const double apart = T.norm();
  double gap = apart - ha.norm() - hb.norm();
  if (apart > 0.0) {
    // The line through the centres: for boxes apart diagonally it is nearly the direction of
    // their closest points, where the face and edge axes below all underestimate the gap.
    const Vec3 u = T / apart;
    const double ra = std::abs(u[0]) * ha[0] + std::abs(u[1]) * ha[1] + std::abs(u[2]) * ha[2];
    double rb = 0.0;
    for (int j = 0; j < 3; ++j) rb += std::abs(u[0] * B(0, j) + u[1] * B(1, j) + u[2] * B(2, j)) * hb[j];
    gap = std::max(gap, apart - ra - rb);
  }
  for (int i = 0; i < 3; ++i) {
    gap = std::max(gap, std::abs(T[i]) - ha[i] - (abs_B(i, 0) * hb[0] + abs_B(i, 1) * hb[1] + abs_B(i, 2) * hb[2]));
  }
  for (int j = 0; j < 3; ++j) {
    const double t = T[0] * B(0, j) + T[1] * B(1, j) + T[2] * B(2, j);
    gap = std::max(gap, std::abs(t) - hb[j] - (ha[0] * abs_B(0, j) + ha[1] * abs_B(1, j) + ha[2] * abs_B(2, j)));
  }
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const double len2 = 1.0 - B(i, j) * B(i, j);  // |a_i x b_j|^2 for orthonormal axes
      if (len2 < 1e-6) continue;                   // nearly parallel: no useful axis
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double ra = ha[i1] * abs_B(i2, j) + ha[i2] * abs_B(i1, j);
      const double rb = hb[j1] * abs_B(i, j2) + hb[j2] * abs_B(i, j1);
      gap = std::max(gap, (std::abs(T[i2] * B(i1, j) - T[i1] * B(i2, j)) - ra - rb) / std::sqrt(len2));
    }
  }
  const double scale = ha.sum() + hb.sum() + T.cwiseAbs().sum();
  return gap - kVolumeMargin * scale;
}

// Slab test of a ray against an axis-aligned box (in the ray's frame).
inline bool ray_hits_box(const Ray& ray, const Vec3& lo, const Vec3& hi) {
  double t0 = 0.0, t1 = ray.max_t;
  const double pad = kVolumeMargin * ((hi - lo).cwiseAbs().sum() + ray.origin.cwiseAbs().sum());
  for (int i = 0; i < 3; ++i) {
    if (ray.direction[i] == 0.0) {
      if (ray.origin[i] < lo[i] - pad || ray.origin[i] > hi[i] + pad) return false;
      continue;
    }
    double a = (lo[i] - pad - ray.origin[i]) * ray.inv_direction[i];
    double b = (hi[i] + pad - ray.origin[i]) * ray.inv_direction[i];
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1 * (1 + kVolumeMargin) + kVolumeMargin) return false;
  }
  return true;
}

// Principal axes of points (columns, by decreasing variance), a right-handed rotation.
Mat3 principal_axes(const Vec3* points, std::size_t n);

}  // namespace detail

// ------------------------------------------------------------ what every volume type declares

// The enclosing volume of n points (specialised in each volume's header).
template <class BV>
BV fit_volume(const Vec3* points, std::size_t n);

// Volume types whose nodes the collision traversal carries into the other frame once per query.
template <class BV>
struct CarriesVolumes : std::false_type {};

// A box (axes as columns, centre, half extents) that contains the volume: for sampling it.
struct EnclosingBox {
  Mat3 axes = Mat3::Identity();
  Vec3 center = Vec3::Zero();
  Vec3 half = Vec3::Zero();
};

// Human-readable names for reports.
template <class BV>
const char* volume_name();

}  // namespace bvh_collision
