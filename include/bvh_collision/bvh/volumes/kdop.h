// Discrete oriented polytopes (k = 14, 18, 26): slabs along fixed integer directions.
#pragma once

#include "bvh_collision/bvh/volumes/common.h"

namespace bvh_collision {

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

template <>
Kdop14 fit_volume<Kdop14>(const Vec3* points, std::size_t n);
template <>
Kdop18 fit_volume<Kdop18>(const Vec3* points, std::size_t n);
template <>
Kdop26 fit_volume<Kdop26>(const Vec3* points, std::size_t n);

template <int K>
bool contains(const Kdop<K>& v, const Vec3& p) {
  const auto& n = KdopDirections<K>::get();
  for (int i = 0; i < Kdop<K>::kSlabs; ++i) {
    const double d = n[i].dot(p), pad = kVolumeMargin * (std::abs(d) + v.hi[i] - v.lo[i]);
    if (d < v.lo[i] - pad || d > v.hi[i] + pad) return false;
  }
  return true;
}
template <int K>
EnclosingBox enclosing_box(const Kdop<K>& v) { return {Mat3::Identity(), v.box_center(), v.box_half()}; }

}  // namespace bvh_collision
