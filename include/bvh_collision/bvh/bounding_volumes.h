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
// relative margin far above rounding error, so touching geometry is never pruned
// (geometry/safety_margin.h states the policy). One header per type under volumes/.
#pragma once

#include "bvh_collision/bvh/volumes/aabb.h"
#include "bvh_collision/bvh/volumes/kdop.h"
#include "bvh_collision/bvh/volumes/obb.h"
#include "bvh_collision/bvh/volumes/rss.h"
#include "bvh_collision/bvh/volumes/sphere.h"
