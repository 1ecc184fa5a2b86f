// Queries on BVHs: collision and distance between two meshes under poses, ray casting, and point
// containment for closed meshes. Semantics follow docs/design.md:
//  - touching is collision; with padding p a pair collides when its distance d <= p;
//  - tolerance eps: collision is reported whenever d <= p and may be reported when d <= p + eps
//    (never a false negative); eps = 0 is exact;
//  - closed meshes are solids: one wholly inside the other collides (distance 0).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "bvh_collision/bvh/bvh.h"

namespace bvh_collision {

// The textbook's cost terms: T = Nu*Cu + Nv*Cv + Np*Cp.
struct QueryStats {
  std::uint64_t volume_updates = 0;   // Nu: volumes carried into another frame
  std::uint64_t volume_tests = 0;     // Nv: volume overlap / distance-bound tests
  std::uint64_t primitive_tests = 0;  // Np: triangle pair tests
  std::uint64_t pair_tests = 0;       // Nq: shape pairs a query took past its broad phase (set above the BVH)
  QueryStats& operator+=(const QueryStats& o) {
    volume_updates += o.volume_updates;
    volume_tests += o.volume_tests;
    primitive_tests += o.primitive_tests;
    pair_tests += o.pair_tests;
    return *this;
  }
};

struct CollisionRequest {
  double padding = 0.0;
  double tolerance = 0.0;
  std::size_t max_contacts = 0;  // 0: boolean, stop at the first collision
  bool solids = true;            // closed meshes bound solids (containment counts)
};

struct MeshContact {
  Vec3 position = Vec3::Zero();  // world frame
  Vec3 normal = Vec3::UnitZ();   // world frame, from b towards a
  double depth = 0.0;            // penetration estimate; 0 for touching, padding and containment
  std::int32_t triangle_a = -1, triangle_b = -1;  // mesh triangle indices; -1 for containment
};

struct CollisionResult {
  bool collision = false;
  // Decided by the tolerance without reaching triangles: the distance is <= padding + tolerance.
  bool within_tolerance = false;
  std::vector<MeshContact> contacts;
  QueryStats stats;
};

struct DistanceRequest {
  double tolerance = 0.0;  // the reported distance may exceed the true one by this much
  bool solids = true;      // closed meshes bound solids: one inside the other is at distance 0
  // Only distances below this matter: the search prunes everything at or beyond it and reports
  // infinity when nothing is closer (a robot query passes its best pair so far).
  double upper_bound = std::numeric_limits<double>::infinity();
};

struct DistanceResult {
  double distance = std::numeric_limits<double>::infinity();
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  // world frame witnesses
  std::int32_t triangle_a = -1, triangle_b = -1;
  QueryStats stats;
};

struct RayHit {
  bool hit = false;
  double distance = std::numeric_limits<double>::infinity();  // along the unit direction
  Vec3 point = Vec3::Zero();
  std::int32_t triangle = -1;
};

template <class BV>
CollisionResult collide(const Bvh<BV>& a, const Transform& pose_a, const Bvh<BV>& b,
                        const Transform& pose_b, const CollisionRequest& request = {});

template <class BV>
DistanceResult distance(const Bvh<BV>& a, const Transform& pose_a, const Bvh<BV>& b,
                        const Transform& pose_b, const DistanceRequest& request = {});

// The point of the mesh (pose in world) closest to p (world), if closer than `upper_bound`:
// distance, the closest point in `point_b`, its triangle in `triangle_b` (point_a = p).
template <class BV>
DistanceResult point_distance(const Bvh<BV>& bvh, const Transform& pose, const Vec3& p,
                              double upper_bound = std::numeric_limits<double>::infinity());

// Is some point of the mesh (pose in world) closer than `radius` to p (world)? The answer of
// point_distance(bvh, pose, p, radius).distance < radius, but the walk stops at the first triangle
// found closer: a yes/no question near a surface costs a few triangles, not the nearest one's search.
template <class BV>
bool point_within(const Bvh<BV>& bvh, const Transform& pose, const Vec3& p, double radius, QueryStats* stats = nullptr);

// The triangles (indices into bvh.triangles()) with a point closer than `radius` to p (the mesh's
// own frame), each as point_within would find it, appended to `out`; false when there are more
// than `max_count` (out then holds some of them).
template <class BV>
bool triangles_near(const Bvh<BV>& bvh, const Vec3& p, double radius, std::size_t max_count,
                    std::vector<std::int32_t>& out, QueryStats* stats = nullptr);

// First hit (or, with any_hit, some hit) of the ray origin + s * direction, 0 <= s <= max_range
// (direction need not be unit; distances are along the unit direction), in world frame.
template <class BV>
RayHit raycast(const Bvh<BV>& bvh, const Transform& pose, const Vec3& origin, const Vec3& direction,
               double max_range, bool any_hit = false, QueryStats* stats = nullptr);

// Is the point (in the mesh's own frame) inside or on the closed mesh? Decided by the winding
// number: exact ray crossings (orient3d) counted with their orientation, so a mesh of several
// overlapping closed shells is solid where they overlap, and a cavity (an inward shell) is not.
// A ray grazing an edge or vertex is replaced by another one. For a mesh that is not closed,
// answers whether the point lies on it.
template <class BV>
bool contains_point(const Bvh<BV>& bvh, const Vec3& point, QueryStats* stats = nullptr);

// The winding number of the closed mesh around `point` (its own frame): 0 outside, 1 inside one
// shell, 2 where two overlap, as contains_point counts it; nothing for a mesh that is not closed,
// a point on the surface, or when no ray decides.
template <class BV>
std::optional<int> winding_number(const Bvh<BV>& bvh, const Vec3& point, QueryStats* stats = nullptr);

// How the segment a -> b crosses triangle t, exactly: 0 not at all, +1 or -1 through its inside
// (so that for a closed mesh winding_number(b) = winding_number(a) - the sum over its triangles),
// nothing when it touches an edge or a vertex, or starts or ends on the triangle.
std::optional<int> signed_crossing(const Vec3& a, const Vec3& b, const Triangle& t);

}  // namespace bvh_collision
