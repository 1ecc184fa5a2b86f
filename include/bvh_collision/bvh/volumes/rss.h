// Rectangle swept sphere.
#pragma once

#include "bvh_collision/bvh/volumes/common.h"

namespace bvh_collision {

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

template <>
Rss fit_volume<Rss>(const Vec3* points, std::size_t n);
bool contains(const Rss& v, const Vec3& p);
inline EnclosingBox enclosing_box(const Rss& v) {
  return {v.axes, v.center, Vec3(v.half[0] + v.radius, v.half[1] + v.radius, v.radius)};
}

}  // namespace bvh_collision
