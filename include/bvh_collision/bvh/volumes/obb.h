// Oriented bounding box: the default volume of link and object hierarchies.
#pragma once

#include "bvh_collision/bvh/volumes/common.h"

namespace bvh_collision {

struct Obb {
  Mat3 axes = Mat3::Identity();  // columns: the box's axes in the mesh frame
  Vec3 center = Vec3::Zero();
  Vec3 half = Vec3::Zero();
  double radius = 0.0;  // half.norm(): the circumscribed sphere, a cheap first test
};

inline Vec3 center(const Obb& b) { return b.center; }
inline double radius(const Obb& b) { return b.radius; }
Obb merge(const Obb& a, const Obb& b);

// b carried into a's mesh frame (the textbook's "volume update"): done once per node and query.
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

template <>
struct CarriesVolumes<Obb> : std::true_type {};

inline bool ray_hits(const Obb& b, const Ray& ray) {
  const Ray local(b.axes.transpose() * (ray.origin - b.center), b.axes.transpose() * ray.direction, ray.max_t);
  return detail::ray_hits_box(local, -b.half, b.half);
}

template <>
Obb fit_volume<Obb>(const Vec3* points, std::size_t n);
// fit_volume<Obb> is fit_obb(points, n, true). Without the rotation search the axes are the
// better of the principal and the mesh axes (an edge-aligned frame for a single triangle):
// the hierarchies of very large meshes, where the search would dominate loading.
Obb fit_obb(const Vec3* points, std::size_t n, bool search_rotations);
bool contains(const Obb& v, const Vec3& p);
inline EnclosingBox enclosing_box(const Obb& v) { return {v.axes, v.center, v.half}; }

}  // namespace bvh_collision
