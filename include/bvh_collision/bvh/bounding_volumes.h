// Bounding volumes: AABB, OBB, sphere, k-DOP (k = 14, 18, 26) and RSS.
//
// Every volume type provides the same free functions, so that the builders and traversals are
// templates over the type (no virtual calls in the hot loops):
//   BV fit_volume<BV>(const Vec3* points, size_t n)     enclosing volume of points
//   BV merge(const BV&, const BV&)                     enclosing volume of two volumes
//   bool overlap(a, b, frame, padding)                 conservative: false only when apart by
//                                                      more than padding
//   double distance_lower_bound(a, b, frame)           <= the distance between the volumes
//   double radius(v), Vec3 center(v)
//   bool ray_hits(v, ray)                               conservative ray test
// `a` is in the first mesh's frame, `b` in the second's; `frame` holds the pose of the second
// mesh in the first mesh's frame, prepared once per query. Tests err on the side of overlap by a
// relative margin far above rounding error, so touching geometry is never pruned.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// The volume tests sit in the innermost traversal loops; GCC's -O2 inliner otherwise keeps some
// of them out of line.
#define BVH_HOT [[gnu::always_inline]] inline

// Relative slack for conservative comparisons (thousands of ulps; negligible for pruning).
constexpr double kVolumeMargin = 1e-12;

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
  for (int k = 0; k < 9; ++k) r.data()[k] = std::abs(m.data()[k]) + 1e-12;
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

// ------------------------------------------------------------------------------------------ AABB

struct Aabb {
  Vec3 min = Vec3::Constant(std::numeric_limits<double>::infinity());
  Vec3 max = Vec3::Constant(-std::numeric_limits<double>::infinity());

  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
  Vec3 half() const { return 0.5 * (max - min); }
  bool valid() const { return (min.array() <= max.array()).all(); }
};

inline Vec3 center(const Aabb& b) { return 0.5 * (b.min + b.max); }
inline double radius(const Aabb& b) { return b.half().norm(); }
inline Aabb merge(const Aabb& a, const Aabb& b) { return {a.min.cwiseMin(b.min), a.max.cwiseMax(b.max)}; }

BVH_HOT bool overlap(const Aabb& a, const Aabb& b, const RelativeFrame& f, double padding) {
  if (f.pure_translation) {
    const Vec3 bmin = b.min + f.t, bmax = b.max + f.t;
    const double slack = padding + kVolumeMargin * (a.max - a.min + bmax - bmin + a.min.cwiseAbs()).sum();
    return (a.min.array() <= bmax.array() + slack).all() && (bmin.array() <= a.max.array() + slack).all();
  }
  return detail::boxes_overlap(f.apply(center(b)) - center(a), a.half(), f.R, f.abs_R, b.half(), padding);
}

inline double distance_lower_bound(const Aabb& a, const Aabb& b, const RelativeFrame& f) {
  return detail::boxes_distance_lower_bound(f.apply(center(b)) - center(a), a.half(), f.R, f.abs_R, b.half());
}

inline bool ray_hits(const Aabb& b, const Ray& ray) { return detail::ray_hits_box(ray, b.min, b.max); }

// ------------------------------------------------------------------------------------------- OBB

struct Obb {
  Mat3 axes = Mat3::Identity();  // columns: the box's axes in the mesh frame
  Vec3 center = Vec3::Zero();
  Vec3 half = Vec3::Zero();
  double radius = 0.0;  // half.norm(): the circumscribed sphere, a cheap first test
};

inline Vec3 center(const Obb& b) { return b.center; }
inline double radius(const Obb& b) { return b.radius; }
Obb merge(const Obb& a, const Obb& b);

// b carried into a's mesh frame (the seed's "volume update"): done once per node and query.
BVH_HOT Obb carry(const Obb& b, const RelativeFrame& f) {
  return {detail::times(f.R, b.axes), f.apply(b.center), b.half, b.radius};
}

// Both boxes in the same (a's mesh) frame. The rows of b's axes in a's box frame are computed
// as the separating-axis test reaches them, so a pair rejected early costs a third of it.
BVH_HOT bool overlap_carried(const Obb& a, const Obb& b, double padding) {
  const Vec3 d = b.center - a.center;
  const double reach = a.radius + b.radius + padding;
  const double d2 = d.squaredNorm();
  if (d2 > reach * reach * (1 + 4 * kVolumeMargin) + kVolumeMargin) return false;
  // |T|_1 <= sqrt(3)|d| and |h|_1 <= sqrt(3) radius: a margin at least kVolumeMargin * scale.
  const double s = padding + 2.0 * kVolumeMargin * (a.radius + b.radius + std::sqrt(d2));
  Mat3 B, abs_B;
  Vec3 T;
  for (int i = 0; i < 3; ++i) {
    const Vec3 ai = a.axes.col(i);
    T[i] = ai.x() * d.x() + ai.y() * d.y() + ai.z() * d.z();
    double rb = 0.0;
    for (int j = 0; j < 3; ++j) {
      B(i, j) = ai.x() * b.axes(0, j) + ai.y() * b.axes(1, j) + ai.z() * b.axes(2, j);
      abs_B(i, j) = std::abs(B(i, j)) + 1e-12;
      rb += abs_B(i, j) * b.half[j];
    }
    if (std::abs(T[i]) > a.half[i] + rb + s) return false;
  }
  return detail::boxes_overlap(T, a.half, B, abs_B, b.half, padding);
}

BVH_HOT bool overlap(const Obb& a, const Obb& b, const RelativeFrame& f, double padding) {
  return overlap_carried(a, carry(b, f), padding);
}

inline double distance_lower_bound(const Obb& a, const Obb& b, const RelativeFrame& f) {
  const Obb c = carry(b, f);
  const Mat3 B = detail::transpose_times(a.axes, c.axes);
  return detail::boxes_distance_lower_bound(detail::transpose_times(a.axes, Vec3(c.center - a.center)), a.half, B,
                                            detail::abs_plus_epsilon(B), b.half);
}

// Volume types whose nodes the collision traversal carries into the other frame once per query.
template <class BV>
struct CarriesVolumes : std::false_type {};
template <>
struct CarriesVolumes<Obb> : std::true_type {};

inline bool ray_hits(const Obb& b, const Ray& ray) {
  const Ray local(b.axes.transpose() * (ray.origin - b.center), b.axes.transpose() * ray.direction, ray.max_t);
  return detail::ray_hits_box(local, -b.half, b.half);
}

// ---------------------------------------------------------------------------------------- sphere

struct Sphere {
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
};

inline Vec3 center(const Sphere& s) { return s.center; }
inline double radius(const Sphere& s) { return s.radius; }

// The smallest sphere enclosing both (the enclosing-sphere formula), slightly enlarged.
inline Sphere merge(const Sphere& a, const Sphere& b) {
  const Vec3 d = b.center - a.center;
  const double dist = d.norm();
  if (dist + b.radius <= a.radius) return a;
  if (dist + a.radius <= b.radius) return b;
  const double r = 0.5 * (dist + a.radius + b.radius);
  Sphere s;
  s.center = a.center + ((r - a.radius) / dist) * d;
  s.radius = r * (1 + kVolumeMargin) + kVolumeMargin * s.center.cwiseAbs().sum();
  return s;
}

inline bool overlap(const Sphere& a, const Sphere& b, const RelativeFrame& f, double padding) {
  const double reach = a.radius + b.radius + padding;
  const double d2 = (f.apply(b.center) - a.center).squaredNorm();
  return d2 <= reach * reach * (1 + 4 * kVolumeMargin) + kVolumeMargin;
}

inline double distance_lower_bound(const Sphere& a, const Sphere& b, const RelativeFrame& f) {
  const double d = (f.apply(b.center) - a.center).norm();
  return (d - a.radius - b.radius) - kVolumeMargin * (d + a.radius + b.radius);
}

inline bool ray_hits(const Sphere& s, const Ray& ray) {
  const Vec3 m = ray.origin - s.center;
  const double dd = ray.direction.squaredNorm();
  const double t = std::clamp(-m.dot(ray.direction) / dd, 0.0, ray.max_t);
  const double r = s.radius * (1 + kVolumeMargin) + kVolumeMargin * m.norm();
  return (m + t * ray.direction).squaredNorm() <= r * r;
}

// ----------------------------------------------------------------------------------------- k-DOP

// Slab directions of a k-DOP: the 3 axes, then (k=14) the 4 cube diagonals, (k=18) the 6 edge
// diagonals, (k=26) both. Integer directions: projections of a point are sums, no products.
template <int K>
struct KdopDirections {
  static_assert(K == 14 || K == 18 || K == 26, "k-DOP with k = 14, 18 or 26");
  static constexpr int kSlabs = K / 2;
  static const std::array<Vec3, kSlabs>& get() {
    static const std::array<Vec3, kSlabs> dirs = [] {
      std::array<Vec3, kSlabs> d;
      const Vec3 all[13] = {{1, 0, 0},  {0, 1, 0},  {0, 0, 1},  {1, 1, 1},  {1, 1, -1},
                            {1, -1, 1}, {-1, 1, 1}, {1, 1, 0},  {1, 0, 1},  {0, 1, 1},
                            {1, -1, 0}, {1, 0, -1}, {0, 1, -1}};
      const int first_extra = (K == 18) ? 7 : 3;  // 18-DOP skips the cube diagonals
      for (int i = 0; i < 3; ++i) d[i] = all[i];
      for (int i = 3; i < kSlabs; ++i) d[i] = all[first_extra + i - 3];
      return d;
    }();
    return dirs;
  }
};

template <int K>
struct Kdop {
  static constexpr int kSlabs = K / 2;
  std::array<double, kSlabs> lo, hi;  // lo[i] <= n_i . p <= hi[i] for every point p

  Kdop() {
    lo.fill(std::numeric_limits<double>::infinity());
    hi.fill(-std::numeric_limits<double>::infinity());
  }
  void extend(const Vec3& p) {
    const auto& n = KdopDirections<K>::get();
    for (int i = 0; i < kSlabs; ++i) {
      const double d = n[i].dot(p);
      lo[i] = std::min(lo[i], d);
      hi[i] = std::max(hi[i], d);
    }
  }
  // The first three slabs are the AABB.
  Vec3 box_center() const { return 0.5 * Vec3(lo[0] + hi[0], lo[1] + hi[1], lo[2] + hi[2]); }
  Vec3 box_half() const { return 0.5 * Vec3(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]); }
};

template <int K>
Vec3 center(const Kdop<K>& k) { return k.box_center(); }
template <int K>
double radius(const Kdop<K>& k) { return k.box_half().norm(); }

template <int K>
Kdop<K> merge(const Kdop<K>& a, const Kdop<K>& b) {
  Kdop<K> m;
  for (int i = 0; i < Kdop<K>::kSlabs; ++i) {
    m.lo[i] = std::min(a.lo[i], b.lo[i]);
    m.hi[i] = std::max(a.hi[i], b.hi[i]);
  }
  return m;
}

namespace detail {
// Does box (center c, half h, axes given by rows-abs `abs_axes_dot`) projected on the k-DOP's
// directions stay clear of the k-DOP's slabs? Direction n_i's projection radius for a box with
// axes B and half h is sum_j |n_i . B_j| h_j.
template <int K>
bool kdop_box_overlap(const Kdop<K>& k, const Vec3& c, const Vec3& h, const Mat3& B, double padding) {
  const auto& n = KdopDirections<K>::get();
  for (int i = 0; i < Kdop<K>::kSlabs; ++i) {
    const double p = n[i].dot(c);
    const double r = (B.transpose() * n[i]).cwiseAbs().dot(h);
    const double slack = padding * n[i].norm() + kVolumeMargin * (std::abs(p) + r + k.hi[i] - k.lo[i]);
    if (p - r > k.hi[i] + slack || p + r < k.lo[i] - slack) return false;
  }
  return true;
}
}  // namespace detail

template <int K>
bool overlap(const Kdop<K>& a, const Kdop<K>& b, const RelativeFrame& f, double padding) {
  const auto& n = KdopDirections<K>::get();
  if (f.pure_translation) {
    for (int i = 0; i < Kdop<K>::kSlabs; ++i) {
      const double shift = n[i].dot(f.t);
      const double slack = padding * n[i].norm() +
                           kVolumeMargin * (std::abs(shift) + std::abs(a.hi[i]) + std::abs(b.hi[i]) + std::abs(a.lo[i]));
      if (b.lo[i] + shift > a.hi[i] + slack || b.hi[i] + shift < a.lo[i] - slack) return false;
    }
    return true;
  }
  // Rotated: a's k-DOP against b's box (its first three slabs) carried into a's frame, and b's
  // k-DOP against a's box carried into b's frame. Conservative: cross axes are not tested.
  if (!detail::kdop_box_overlap(a, f.apply(b.box_center()), b.box_half(), f.R, padding)) return false;
  const Mat3 Rt = f.R.transpose();
  return detail::kdop_box_overlap(b, Rt * (a.box_center() - f.t), a.box_half(), Rt, padding);
}

template <int K>
double distance_lower_bound(const Kdop<K>& a, const Kdop<K>& b, const RelativeFrame& f) {
  const auto& n = KdopDirections<K>::get();
  const Vec3 cb = f.apply(b.box_center());
  const Vec3 hb = b.box_half();
  double gap = detail::boxes_distance_lower_bound(cb - a.box_center(), a.box_half(), f.R, f.abs_R, hb);
  for (int i = 3; i < Kdop<K>::kSlabs; ++i) {
    const double p = n[i].dot(cb);
    const double r = (f.R.transpose() * n[i]).cwiseAbs().dot(hb);
    const double scale = std::abs(p) + r + std::abs(a.hi[i]) + std::abs(a.lo[i]);
    gap = std::max(gap, (std::max(p - r - a.hi[i], a.lo[i] - p - r) - kVolumeMargin * scale) / n[i].norm());
  }
  return gap;
}

template <int K>
bool ray_hits(const Kdop<K>& k, const Ray& ray) {
  const auto& n = KdopDirections<K>::get();
  double t0 = 0.0, t1 = ray.max_t;
  for (int i = 0; i < Kdop<K>::kSlabs; ++i) {
    const double o = n[i].dot(ray.origin), d = n[i].dot(ray.direction);
    const double pad = kVolumeMargin * (std::abs(o) + std::abs(k.lo[i]) + std::abs(k.hi[i]) + 1.0);
    if (d == 0.0) {
      if (o < k.lo[i] - pad || o > k.hi[i] + pad) return false;
      continue;
    }
    double a = (k.lo[i] - pad - o) / d, b = (k.hi[i] + pad - o) / d;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1 * (1 + kVolumeMargin) + kVolumeMargin) return false;
  }
  return true;
}

using Kdop14 = Kdop<14>;
using Kdop18 = Kdop<18>;
using Kdop26 = Kdop<26>;

// ------------------------------------------------------------------------------------------- RSS

// Rectangle swept sphere: the points within `radius` of a rectangle with half lengths half[0],
// half[1] along axes.col(0), axes.col(1), centred at `center` (axes.col(2) is its normal).
struct Rss {
  Mat3 axes = Mat3::Identity();
  Vec3 center = Vec3::Zero();
  double half[2] = {0.0, 0.0};
  double radius = 0.0;
};

inline Vec3 center(const Rss& r) { return r.center; }
inline double radius(const Rss& r) { return std::hypot(r.half[0], r.half[1]) + r.radius; }
Rss merge(const Rss& a, const Rss& b);

namespace detail {
// b's rectangle frame in a's rectangle frame.
BVH_HOT void rect_in_rect(const Rss& a, const Rss& b, const RelativeFrame& f, Mat3& B, Mat3& abs_B, Vec3& T) {
  B = transpose_times(a.axes, times(f.R, b.axes));
  abs_B = abs_plus_epsilon(B);
  T = transpose_times(a.axes, Vec3(f.apply(b.center) - a.center));
}
}  // namespace detail

BVH_HOT bool overlap(const Rss& a, const Rss& b, const RelativeFrame& f, double padding) {
  // The rectangles as flat boxes: separated by more than both radii plus padding along an axis.
  Mat3 B, abs_B;
  Vec3 T;
  detail::rect_in_rect(a, b, f, B, abs_B, T);
  return detail::boxes_overlap(T, Vec3(a.half[0], a.half[1], 0.0), B, abs_B, Vec3(b.half[0], b.half[1], 0.0),
                               padding + a.radius + b.radius);
}

inline double distance_lower_bound(const Rss& a, const Rss& b, const RelativeFrame& f) {
  Mat3 B, abs_B;
  Vec3 T;
  detail::rect_in_rect(a, b, f, B, abs_B, T);
  const double rect = detail::boxes_distance_lower_bound(T, Vec3(a.half[0], a.half[1], 0.0), B, abs_B,
                                                         Vec3(b.half[0], b.half[1], 0.0));
  return rect - a.radius - b.radius - kVolumeMargin * (a.radius + b.radius);
}

inline bool ray_hits(const Rss& r, const Ray& ray) {
  const Ray local(r.axes.transpose() * (ray.origin - r.center), r.axes.transpose() * ray.direction, ray.max_t);
  const Vec3 h(r.half[0] + r.radius, r.half[1] + r.radius, r.radius);
  return detail::ray_hits_box(local, -h, h);
}

// ----------------------------------------------------------------------------------------- fitting

template <class BV>
BV fit_volume(const Vec3* points, std::size_t n);

template <>
Aabb fit_volume<Aabb>(const Vec3* points, std::size_t n);
template <>
Obb fit_volume<Obb>(const Vec3* points, std::size_t n);
template <>
Sphere fit_volume<Sphere>(const Vec3* points, std::size_t n);
template <>
Rss fit_volume<Rss>(const Vec3* points, std::size_t n);
template <>
Kdop14 fit_volume<Kdop14>(const Vec3* points, std::size_t n);
template <>
Kdop18 fit_volume<Kdop18>(const Vec3* points, std::size_t n);
template <>
Kdop26 fit_volume<Kdop26>(const Vec3* points, std::size_t n);

// Does the volume contain p (up to the margin)? For tests and assertions.
bool contains(const Aabb& v, const Vec3& p);
bool contains(const Obb& v, const Vec3& p);
bool contains(const Sphere& v, const Vec3& p);
bool contains(const Rss& v, const Vec3& p);
template <int K>
bool contains(const Kdop<K>& v, const Vec3& p) {
  const auto& n = KdopDirections<K>::get();
  for (int i = 0; i < Kdop<K>::kSlabs; ++i) {
    const double d = n[i].dot(p), pad = kVolumeMargin * (std::abs(d) + v.hi[i] - v.lo[i]);
    if (d < v.lo[i] - pad || d > v.hi[i] + pad) return false;
  }
  return true;
}

// A box (axes as columns, centre, half extents) that contains the volume: for sampling it.
struct EnclosingBox {
  Mat3 axes = Mat3::Identity();
  Vec3 center = Vec3::Zero();
  Vec3 half = Vec3::Zero();
};
inline EnclosingBox enclosing_box(const Aabb& v) { return {Mat3::Identity(), center(v), v.half()}; }
inline EnclosingBox enclosing_box(const Obb& v) { return {v.axes, v.center, v.half}; }
inline EnclosingBox enclosing_box(const Sphere& v) { return {Mat3::Identity(), v.center, Vec3::Constant(v.radius)}; }
inline EnclosingBox enclosing_box(const Rss& v) {
  return {v.axes, v.center, Vec3(v.half[0] + v.radius, v.half[1] + v.radius, v.radius)};
}
template <int K>
EnclosingBox enclosing_box(const Kdop<K>& v) { return {Mat3::Identity(), v.box_center(), v.box_half()}; }

// Human-readable names for reports.
template <class BV>
const char* volume_name();

}  // namespace bvh_collision
