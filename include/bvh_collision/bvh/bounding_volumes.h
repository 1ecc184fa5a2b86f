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

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// Relative slack for conservative comparisons (thousands of ulps; negligible for pruning).
constexpr double kVolumeMargin = 1e-12;

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
    f.abs_R = (b_in_a.R.cwiseAbs().array() + 1e-12).matrix();
    f.pure_translation = b_in_a.R == Mat3::Identity();
    if (f.pure_translation) f.abs_R = Mat3::Identity();
    return f;
  }
  Vec3 apply(const Vec3& p) const { return R * p + t; }
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

// Separating-axis test for two boxes: a axis-aligned with half extents ha at ca; b with axes
// B (columns, in a's frame; abs_B its absolute values) and half extents hb at cb. Returns false
// only when some axis separates them by more than `padding`.
inline bool boxes_overlap(const Vec3& ca, const Vec3& ha, const Mat3& B, const Mat3& abs_B,
                          const Vec3& cb, const Vec3& hb, double padding) {
  const Vec3 T = cb - ca;
  const double scale = ha.sum() + hb.sum() + T.cwiseAbs().sum();
  const double slack = padding + kVolumeMargin * scale;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(T[i]) > ha[i] + abs_B.row(i).dot(hb) + slack) return false;
  }
  for (int j = 0; j < 3; ++j) {
    if (std::abs(T.dot(B.col(j))) > ha.dot(abs_B.col(j)) + hb[j] + slack) return false;
  }
  for (int i = 0; i < 3; ++i) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; ++j) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      const double ra = ha[i1] * abs_B(i2, j) + ha[i2] * abs_B(i1, j);
      const double rb = hb[j1] * abs_B(i, j2) + hb[j2] * abs_B(i, j1);
      if (std::abs(T[i2] * B(i1, j) - T[i1] * B(i2, j)) > ra + rb + slack) return false;
    }
  }
  return true;
}

// A lower bound on the distance between the two boxes: the largest gap along a face axis, or
// between circumscribed spheres, reduced by the margin.
inline double boxes_distance_lower_bound(const Vec3& ca, const Vec3& ha, const Mat3& B,
                                         const Mat3& abs_B, const Vec3& cb, const Vec3& hb) {
  const Vec3 T = cb - ca;
  double gap = T.norm() - ha.norm() - hb.norm();
  for (int i = 0; i < 3; ++i) gap = std::max(gap, std::abs(T[i]) - ha[i] - abs_B.row(i).dot(hb));
  for (int j = 0; j < 3; ++j) gap = std::max(gap, std::abs(T.dot(B.col(j))) - ha.dot(abs_B.col(j)) - hb[j]);
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

inline bool overlap(const Aabb& a, const Aabb& b, const RelativeFrame& f, double padding) {
  if (f.pure_translation) {
    const Vec3 bmin = b.min + f.t, bmax = b.max + f.t;
    const double slack = padding + kVolumeMargin * (a.max - a.min + bmax - bmin + a.min.cwiseAbs()).sum();
    return (a.min.array() <= bmax.array() + slack).all() && (bmin.array() <= a.max.array() + slack).all();
  }
  return detail::boxes_overlap(center(a), a.half(), f.R, f.abs_R, f.apply(center(b)), b.half(), padding);
}

inline double distance_lower_bound(const Aabb& a, const Aabb& b, const RelativeFrame& f) {
  return detail::boxes_distance_lower_bound(center(a), a.half(), f.R, f.abs_R, f.apply(center(b)), b.half());
}

inline bool ray_hits(const Aabb& b, const Ray& ray) { return detail::ray_hits_box(ray, b.min, b.max); }

// ------------------------------------------------------------------------------------------- OBB

struct Obb {
  Mat3 axes = Mat3::Identity();  // columns: the box's axes in the mesh frame
  Vec3 center = Vec3::Zero();
  Vec3 half = Vec3::Zero();
};

inline Vec3 center(const Obb& b) { return b.center; }
inline double radius(const Obb& b) { return b.half.norm(); }
Obb merge(const Obb& a, const Obb& b);

inline bool overlap(const Obb& a, const Obb& b, const RelativeFrame& f, double padding) {
  // b's axes expressed in a's box frame.
  const Mat3 B = a.axes.transpose() * (f.R * b.axes);
  const Mat3 abs_B = (B.cwiseAbs().array() + 1e-12).matrix();
  const Vec3 cb = a.axes.transpose() * (f.apply(b.center) - a.center);
  return detail::boxes_overlap(Vec3::Zero(), a.half, B, abs_B, cb, b.half, padding);
}

inline double distance_lower_bound(const Obb& a, const Obb& b, const RelativeFrame& f) {
  const Mat3 B = a.axes.transpose() * (f.R * b.axes);
  const Mat3 abs_B = (B.cwiseAbs().array() + 1e-12).matrix();
  const Vec3 cb = a.axes.transpose() * (f.apply(b.center) - a.center);
  return detail::boxes_distance_lower_bound(Vec3::Zero(), a.half, B, abs_B, cb, b.half);
}

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
  double gap = detail::boxes_distance_lower_bound(a.box_center(), a.box_half(), f.R, f.abs_R, cb, hb);
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
// Lower bound on the distance between the two rectangles (flat boxes) of a and b.
inline double rectangles_distance_lower_bound(const Rss& a, const Rss& b, const RelativeFrame& f) {
  const Mat3 B = a.axes.transpose() * (f.R * b.axes);
  const Mat3 abs_B = (B.cwiseAbs().array() + 1e-12).matrix();
  const Vec3 cb = a.axes.transpose() * (f.apply(b.center) - a.center);
  return boxes_distance_lower_bound(Vec3::Zero(), Vec3(a.half[0], a.half[1], 0.0), B, abs_B, cb,
                                    Vec3(b.half[0], b.half[1], 0.0));
}
}  // namespace detail

inline bool overlap(const Rss& a, const Rss& b, const RelativeFrame& f, double padding) {
  // The rectangles as flat boxes: separated by more than both radii plus padding along an axis.
  const Mat3 B = a.axes.transpose() * (f.R * b.axes);
  const Mat3 abs_B = (B.cwiseAbs().array() + 1e-12).matrix();
  const Vec3 cb = a.axes.transpose() * (f.apply(b.center) - a.center);
  return detail::boxes_overlap(Vec3::Zero(), Vec3(a.half[0], a.half[1], 0.0), B, abs_B, cb,
                               Vec3(b.half[0], b.half[1], 0.0), padding + a.radius + b.radius);
}

inline double distance_lower_bound(const Rss& a, const Rss& b, const RelativeFrame& f) {
  const double rect = detail::rectangles_distance_lower_bound(a, b, f);
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
