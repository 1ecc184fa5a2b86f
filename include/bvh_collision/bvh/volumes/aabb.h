// Axis-aligned bounding box.
#pragma once

#include "bvh_collision/bvh/volumes/common.h"

namespace bvh_collision {

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

template <>
Aabb fit_volume<Aabb>(const Vec3* points, std::size_t n);
// Does the volume contain p (up to the margin)? For tests and assertions.
bool contains(const Aabb& v, const Vec3& p);
inline EnclosingBox enclosing_box(const Aabb& v) { return {Mat3::Identity(), center(v), v.half()}; }

}  // namespace bvh_collision
