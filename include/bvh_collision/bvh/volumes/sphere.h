// Bounding sphere.
#pragma once

#include "bvh_collision/bvh/volumes/common.h"

namespace bvh_collision {

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

template <>
Sphere fit_volume<Sphere>(const Vec3* points, std::size_t n);
bool contains(const Sphere& v, const Vec3& p);
inline EnclosingBox enclosing_box(const Sphere& v) { return {Mat3::Identity(), v.center, Vec3::Constant(v.radius)}; }

}  // namespace bvh_collision
