#include "bvh_collision/bvh/primitive_queries.h"

#include <algorithm>
#include <cmath>

#include "bvh_collision/bvh/traversal.h"
#include "bvh_collision/geometry/convex_distance.h"
#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {
namespace {

// The primitive's tight box, in the mesh frame.
Obb primitive_box(const Primitive& p, const Transform& p_in_mesh) {
  const Vec3 half = half_extents(p);
  return Obb{p_in_mesh.R, p_in_mesh.t, half, half.norm()};
}

// Asked once no triangle comes within reach, when each connected component of the mesh is wholly
// inside or wholly outside the primitive, and the primitive wholly inside or outside a closed mesh:
// one point of each decides. A primitive is a solid, so a mesh inside it counts whatever
// `solids` says; a primitive inside a closed mesh counts with `solids`. `where` (mesh frame) is
// the point that decided.
bool one_holds_the_other(const Bvh<Obb>& mesh, const Primitive& p, const Transform& p_in_mesh, bool solids,
                         QueryStats& stats, Vec3& where) {
  for (const Vec3& c : mesh.component_points()) {
    if (contains(p, p_in_mesh.R.transpose() * (c - p_in_mesh.t))) {
      where = c;
      return true;
    }
  }
  where = p_in_mesh.t;
  return solids && mesh.closed() && contains_point(mesh, p_in_mesh.t, &stats);
}

// Does a corner of the triangle (mesh frame) lie inside the primitive (posed in the mesh frame by
// p_in_mesh) by more than the rounding of carrying it into the primitive's frame? Then the mesh
// meets the solid there, at any padding. Most triangles a deep collision reaches have one, and the
// test costs a few dozen operations against a convex distance's thousands (a tenth of a planner's
// colliding states, with the copies GJK no longer makes).
bool corner_inside(const Triangle& t, const Primitive& p, const Transform& p_in_mesh) {
  for (int k = 0; k < 3; ++k) {
    const Vec3 local = p_in_mesh.R.transpose() * (t[k] - p_in_mesh.t);
    if (inscribed_depth(p, local) > pose_margin(t[k].norm() + p_in_mesh.t.norm() + local.norm())) return true;
  }
  return false;
}

MeshContact contact_from(const ConvexDistance& d, const Triangle& t, const Transform& pose_mesh, const Vec3& p_centre,
                         std::int32_t triangle) {
  MeshContact c;
  c.position = pose_mesh * (0.5 * (d.on_a + d.on_b));
  Vec3 n = d.on_a - d.on_b;  // from the primitive towards the mesh
  if (!(n.norm() > 0)) {
    n = (t[1] - t[0]).cross(t[2] - t[0]);
    if (n.dot(t[0] - p_centre) < 0) n = -n;
  }
  c.normal = n.norm() > 0 ? Vec3(pose_mesh.R * n.normalized()) : Vec3(Vec3::UnitZ());
  c.triangle_a = triangle;
  return c;
}

}  // namespace

CollisionResult collide(const Bvh<Obb>& mesh, const Transform& pose_mesh, const Primitive& primitive,
                        const Transform& pose_primitive, const CollisionRequest& request) {
  CollisionResult result;
  if (mesh.empty()) return result;
  const Transform rel = relative_transform(pose_mesh, pose_primitive);
  const Obb box = primitive_box(primitive, rel);
  const ConvexShape shape = ConvexShape::of(primitive);
  auto visit = [&](const BvhNode<Obb>& n) {
    ++result.stats.volume_tests;
    return overlap_carried(n.volume, box, request.padding) ? Visit::kEnter : Visit::kSkip;
  };
  depth_first(mesh, visit, [&](const BvhNode<Obb>& n) {
    for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
      ++result.stats.primitive_tests;
      const Triangle& t = mesh.triangles()[i];
      if (request.max_contacts == 0 && corner_inside(t, primitive, rel)) {  // boolean: no convex distance needed
        result.collision = true;
        return true;
      }
      const ConvexDistance d = convex_distance(ConvexShape::of(t), shape, rel, request.padding);
      if (d.lower_bound > request.padding) continue;
      result.collision = true;
      if (result.contacts.size() < request.max_contacts) {
        result.contacts.push_back(contact_from(d, t, pose_mesh, rel.t, mesh.triangle_id(i)));
      }
      if (result.contacts.size() >= request.max_contacts) return true;
    }
    return false;
  });
  if (result.collision) return result;
  if (Vec3 where; one_holds_the_other(mesh, primitive, rel, request.solids, result.stats, where)) {
    result.collision = true;
    if (request.max_contacts > 0) {
      MeshContact c;
      c.position = pose_mesh * where;
      result.contacts.push_back(c);
    }
  }
  return result;
}

DistanceResult distance(const Bvh<Obb>& mesh, const Transform& pose_mesh, const Primitive& primitive,
                        const Transform& pose_primitive, const DistanceRequest& request) {
  DistanceResult result;
  if (mesh.empty()) return result;
  const Transform rel = relative_transform(pose_mesh, pose_primitive);
  const Obb box = primitive_box(primitive, rel);
  const RelativeFrame same = RelativeFrame::from(Transform::Identity());
  const ConvexShape shape = ConvexShape::of(primitive);
  double best = request.upper_bound;
  auto bound = [&](std::int32_t n) {
    ++result.stats.volume_tests;
    return distance_lower_bound(mesh.nodes()[n].volume, box, same);
  };
  auto leaf = [&](const BvhNode<Obb>& n) {
    for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
      ++result.stats.primitive_tests;
      // (Each triangle within the tolerance too: what it reports is still a pair of points, at most
      // the tolerance farther apart than the triangle is.)
      const ConvexDistance d = convex_distance(ConvexShape::of(mesh.triangles()[i]), shape, rel,
                                               std::numeric_limits<double>::quiet_NaN(), request.tolerance);
      if (d.distance < best) {
        best = d.distance;
        result.distance = d.distance;
        result.point_a = d.on_a;
        result.point_b = d.on_b;
        result.triangle_a = mesh.triangle_id(i);
      }
    }
    return false;
  };
  // A node that cannot beat `best` by more than the tolerance is not entered.
  nearest_first(mesh, bound, leaf, [&] { return best - request.tolerance; });
  if (result.distance > 0.0) {
    if (Vec3 where; one_holds_the_other(mesh, primitive, rel, request.solids, result.stats, where)) {
      result.distance = 0.0;
      result.point_a = result.point_b = where;
      result.triangle_a = -1;
    }
  }
  result.point_a = pose_mesh * result.point_a;
  result.point_b = pose_mesh * result.point_b;
  return result;
}

}  // namespace bvh_collision
