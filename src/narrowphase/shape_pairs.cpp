// The shape-pair dispatch table (detail/shape_pairs.h): one entry per pair of shape kinds.
#include "bvh_collision/narrowphase/shape_pairs.h"

#include <algorithm>
#include <array>
#include <cmath>

#include "bvh_collision/bvh/primitive_queries.h"
#include "bvh_collision/geometry/convex_distance.h"
#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {
namespace {

using CollideFn = bool (*)(const ShapeRef&, const Transform&, const ShapeRef&, const Transform&, const PairRequest&,
                           std::vector<MeshContact>*, QueryStats&);
using DistanceFn = double (*)(const ShapeRef&, const Transform&, const ShapeRef&, const Transform&, double, bool,
                              Vec3&, Vec3&, QueryStats&, double);

Vec3 unit_or_z(const Vec3& v) { return v.norm() > 0 ? Vec3(v.normalized()) : Vec3(Vec3::UnitZ()); }

// ---------------------------------------------------------------- sphere and sphere: analytic

bool sphere_sphere_collide(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                           const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats&) {
  const double ra = a.primitive.radius, rb = b.primitive.radius;
  const Vec3 d = pa.t - pb.t;
  const bool hit = d.norm() <= ra + rb + request.padding;
  if (hit && contacts && request.max_contacts > 0) {
    const Vec3 normal = unit_or_z(d);
    contacts->push_back({pb.t + normal * rb, normal, std::max(0.0, ra + rb - d.norm()), -1, -1});
  }
  return hit;
}

double sphere_sphere_distance(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double,
                              bool, Vec3& wa, Vec3& wb, QueryStats&, double) {
  const double ra = a.primitive.radius, rb = b.primitive.radius;
  const double gap = (pb.t - pa.t).norm();
  const Vec3 dir = unit_or_z(pb.t - pa.t);
  wa = pa.t + dir * ra;
  wb = pb.t - dir * rb;
  const double d = std::max(0.0, gap - ra - rb);
  if (d == 0.0) {  // overlapping: the middle of the centre line's stretch inside both
    const double lo = std::max(-ra, gap - rb), hi = std::min(ra, gap + rb);
    wa = wb = pa.t + dir * (0.5 * (lo + hi));
  }
  return d;
}

// ---------------------------------------------------- two primitives: certified convex distance

bool primitives_collide(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                        const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  ++stats.primitive_tests;
  const ConvexDistance d = convex_distance(ConvexShape::of(a.primitive), ConvexShape::of(b.primitive),
                                           relative_transform(pa, pb), request.padding);
  if (d.lower_bound > request.padding) return false;
  if (contacts && request.max_contacts > 0) {
    const Vec3 n = d.distance > 0 ? Vec3(d.on_a - d.on_b) : Vec3(-relative_transform(pa, pb).t);
    contacts->push_back({pa * (0.5 * (d.on_a + d.on_b)), pa.R * unit_or_z(n), 0.0, -1, -1});
  }
  return true;
}

double primitives_distance(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double,
                           bool, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  ++stats.primitive_tests;
  const ConvexDistance d = convex_distance(ConvexShape::of(a.primitive), ConvexShape::of(b.primitive),
                                           relative_transform(pa, pb), std::numeric_limits<double>::quiet_NaN(), tolerance);
  wa = pa * d.on_a;
  wb = pa * (d.intersecting ? d.on_a : d.on_b);
  return d.intersecting ? 0.0 : d.distance;
}

// ------------------------------------------------ a sphere and a mesh: the mesh's closest point

bool sphere_mesh_collide(const ShapeRef& sphere, const Transform& ps, const ShapeRef& mesh, const Transform& pm,
                         const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  const double reach = sphere.primitive.radius + request.padding;
  const DistanceResult d = point_distance(*mesh.mesh, pm, ps.t, grown_radius(reach));
  stats += d.stats;
  bool hit = d.distance <= reach;
  if (!hit && request.solids) hit = contains_point(*mesh.mesh, pm.inverse() * ps.t, &stats);
  if (hit && contacts && request.max_contacts > 0) {
    MeshContact c;
    c.position = std::isfinite(d.distance) ? d.point_b : ps.t;
    c.normal = unit_or_z(ps.t - c.position);  // from the mesh towards the sphere centre
    c.depth = std::isfinite(d.distance) ? std::max(0.0, sphere.primitive.radius - d.distance) : sphere.primitive.radius;
    contacts->push_back(c);
  }
  return hit;
}

double sphere_mesh_distance(const ShapeRef& sphere, const Transform& ps, const ShapeRef& mesh, const Transform& pm,
                            double best, bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double) {
  const double r = sphere.primitive.radius;
  const DistanceResult d = point_distance(*mesh.mesh, pm, ps.t, best + r);
  stats += d.stats;
  double dist = std::max(0.0, d.distance - r);
  Vec3 on_mesh = d.point_b, on_sphere = ps.t;
  if (std::isfinite(d.distance) && d.distance > 0) on_sphere = ps.t + (d.point_b - ps.t) * (r / d.distance);
  if (dist == 0.0) on_sphere = on_mesh;  // the mesh point is inside the sphere: common to both
  if (solids && contains_point(*mesh.mesh, pm.inverse() * ps.t, &stats)) {
    dist = 0.0;
    on_mesh = on_sphere = ps.t;
  }
  wa = on_sphere;
  wb = on_mesh;
  return dist;
}

// ------------------------------------- a mesh and another primitive: the BVH against the shape

// The BVH layer's request for a pair request; contacts only when someone takes them.
CollisionRequest collision_request(const PairRequest& request, bool want_contacts) {
  CollisionRequest r;
  r.padding = request.padding;
  r.tolerance = request.tolerance;
  r.max_contacts = want_contacts ? request.max_contacts : 0;
  r.solids = request.solids;
  return r;
}

// A mesh (its solid too) lies in its convex hull: a hull proven farther from the other set than
// the padding settles a boolean as free with no BVH walk, at every tolerance (free is an answer
// the contract allows beyond the padding; the walk could only add a hit within the tolerance,
// which it may also leave out). Near contact the walk goes down to triangles, where the hulls'
// GJK takes a few of its steps (docs/performance.md). Contacts asked for need the walk.
bool hulls_apart(const ConvexShape& a, const ConvexShape& b, const Transform& b_in_a, const PairRequest& request) {
  return convex_distance(a, b, b_in_a, request.padding).lower_bound > request.padding;
}

// The BVH query's contacts already point from b (the primitive) towards a (the mesh).
bool mesh_primitive_collide(const ShapeRef& mesh, const Transform& pm, const ShapeRef& p, const Transform& pp,
                            const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  if (contacts == nullptr && mesh.hull != nullptr &&
      hulls_apart(ConvexShape::of(*mesh.hull), ConvexShape::of(p.primitive), relative_transform(pm, pp), request)) {
    return false;
  }
  const CollisionResult c = collide(*mesh.mesh, pm, p.primitive, pp, collision_request(request, contacts != nullptr));
  stats += c.stats;
  if (contacts) contacts->insert(contacts->end(), c.contacts.begin(), c.contacts.end());
  return c.collision;
}

// A mesh's BVH query once its hull has given `upper` (surface points that far apart: an upper
// bound on the distance, or `best` when there were none): only what beats it is walked.
DistanceRequest below(double upper, bool solids, double tolerance) {
  DistanceRequest request;
  request.solids = solids;
  request.upper_bound = upper;
  request.tolerance = tolerance;
  return request;
}

// The BVH's answer when it beats the surface points (or there were none), else those points.
double nearer(const DistanceResult& d, double best, double upper, const Vec3& upper_a, const Vec3& upper_b, Vec3& wa, Vec3& wb) {
  if (d.distance < upper || upper >= best) {
    wa = d.point_a;
    wb = d.point_b;
    return d.distance;
  }
  wa = upper_a;
  wb = upper_b;
  return upper;
}

// The hull first, as for two meshes (meshes_distance): its distance is a certified lower bound
// that settles most far pairs, and when its closest point lies on the mesh's surface it is the
// mesh's distance, with no BVH walk. (A link a millimetre from a box face took 570 triangle tests
// a query, most of a planner's motion near a shelf.)
double mesh_primitive_distance(const ShapeRef& mesh, const Transform& pm, const ShapeRef& p, const Transform& pp,
                               double best, bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  const Transform p_in_mesh = relative_transform(pm, pp);
  const ConvexShape hull_shape = ConvexShape::of(*mesh.hull), primitive = ConvexShape::of(p.primitive);
  // Stopped once it is known not nearer than `best`; nearer, on to the closest points that the
  // surface test needs (one search: restarting it there took a fifth of pr2's exact distances).
  const ConvexDistance hull = convex_distance(hull_shape, primitive, p_in_mesh, best - tolerance, tolerance, true);
  if (hull.lower_bound >= best - tolerance) return std::max(hull.lower_bound, best);
  double upper = best;
  Vec3 upper_a = Vec3::Zero(), upper_b = Vec3::Zero();
  if (hull.lower_bound > 0.0) {
    // Disjoint: the primitive is outside the hull, so outside the mesh's solid too. The surface
    // point nearest the hull's witness (a hull vertex is a mesh vertex) bounds from above.
    Vec3 q = hull.on_a;
    if (hull.vertex_a < 0) {
      const DistanceResult nearest = point_distance(*mesh.mesh, Transform::Identity(), hull.on_a);
      stats += nearest.stats;
      q = nearest.point_b;
    }
    const double apart = (q - hull.on_b).norm();
    // (Within 1e-13 of the scale: the BVH's answer to rounding. At 1e-10, as two meshes take it,
    // a little faster but a distance that moves by 3e-11 when a pose moves by an ulp.)
    const double scale = mesh.hull->extent + extent(primitive) + p_in_mesh.t.norm();
    if (apart - hull.lower_bound <= std::max(1e-13 * scale, tolerance)) {
      wa = pm * q;
      wb = pm * hull.on_b;
      return apart;
    }
    if (apart < upper) upper = apart, upper_a = pm * q, upper_b = pm * hull.on_b;
  }
  const DistanceResult d = distance(*mesh.mesh, pm, p.primitive, pp, below(upper, solids, tolerance));
  stats += d.stats;
  return nearer(d, best, upper, upper_a, upper_b, wa, wb);
}

// ------------------------------------------------------------------------------ two meshes

// The distance between two link meshes, settled by their convex hulls when it can be: the hulls'
// distance is a certified lower bound on the meshes' (each mesh lies in its hull), and when the
// hulls' closest points lie on the meshes' surfaces, the meshes are no further apart than those
// points, so the two agree and no BVH traversal is needed. Robot links are mostly convex where
// they face each other, so this settles most pairs; the rest take the exact BVH query.
double meshes_distance(const ShapeRef& ma, const Transform& pa, const ShapeRef& mb, const Transform& pb, double best,
                       bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  const Transform b_in_a = relative_transform(pa, pb);
  const ConvexDistance hull = convex_distance(*ma.hull, *mb.hull, b_in_a);
  // Cannot improve on `best` (by more than the tolerance: then `best` stands).
  if (hull.lower_bound >= best - tolerance) return std::max(hull.lower_bound, best);
  // Surface points near the hulls' witnesses: their distance bounds the meshes' from above.
  double upper = best;
  Vec3 upper_a = Vec3::Zero(), upper_b = Vec3::Zero();
  if (hull.lower_bound > 0.0) {
    // Disjoint hulls: neither solid holds the other, so surface and solid distances agree.
    auto nearest_on_mesh = [&](const ShapeRef& mesh, const Transform& pose, const Vec3& p, int vertex) {
      if (vertex >= 0) return p;  // hull vertices are mesh vertices
      const DistanceResult d = point_distance(*mesh.mesh, pose, p);
      stats += d.stats;
      return d.point_b;
    };
    const Vec3 qa = nearest_on_mesh(ma, Transform::Identity(), hull.on_a, hull.vertex_a);
    const Vec3 qb = nearest_on_mesh(mb, b_in_a, hull.on_b, hull.vertex_b);
    const double apart = (qa - qb).norm();
    const double scale = ma.hull->extent + mb.hull->extent + b_in_a.t.norm();
    // Certified: the hulls' distance is the meshes' (or within the tolerance above it).
    if (apart - hull.lower_bound <= std::max(1e-10 * scale, tolerance)) {
      wa = pa * qa;
      wb = pa * qb;
      return apart;
    }
    if (apart < upper) upper = apart, upper_a = pa * qa, upper_b = pa * qb;
  }
  if (hull.intersecting) {
    // Overlapping hulls often mean touching meshes: a depth-first collision query finds a
    // contact far sooner than the distance query, whose bounds are all 0 there.
    CollisionRequest touch;
    touch.max_contacts = 1;
    touch.solids = solids;
    const CollisionResult c = collide(*ma.mesh, pa, *mb.mesh, pb, touch);
    stats += c.stats;
    if (c.collision) {
      wa = wb = c.contacts.empty() ? pa.t : c.contacts.front().position;
      return 0.0;
    }
  }
  // The exact query, only for what beats `upper`: a close upper bound prunes most of it.
  const DistanceResult d = distance(*ma.mesh, pa, *mb.mesh, pb, below(upper, solids, tolerance));
  stats += d.stats;
  return nearer(d, best, upper, upper_a, upper_b, wa, wb);
}

bool meshes_collide(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                    const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  if (contacts == nullptr && a.hull != nullptr && b.hull != nullptr &&
      hulls_apart(ConvexShape::of(*a.hull), ConvexShape::of(*b.hull), relative_transform(pa, pb), request)) {
    return false;
  }
  const CollisionResult c = collide(*a.mesh, pa, *b.mesh, pb, collision_request(request, contacts != nullptr));
  stats += c.stats;
  if (contacts) contacts->insert(contacts->end(), c.contacts.begin(), c.contacts.end());
  return c.collision;
}

// ------------------------------------------------------------ the table and the swapped entries

// An entry written for (b, a), used for (a, b): contact normals and witnesses swap sides.
template <CollideFn F>
bool swapped_collide(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                     const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  const std::size_t first = contacts ? contacts->size() : 0;
  const bool hit = F(b, pb, a, pa, request, contacts, stats);
  if (contacts) {
    for (std::size_t i = first; i < contacts->size(); ++i) {
      MeshContact& c = (*contacts)[i];
      c.normal = -c.normal;
      std::swap(c.triangle_a, c.triangle_b);
    }
  }
  return hit;
}

template <DistanceFn F>
double swapped_distance(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double best,
                        bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  return F(b, pb, a, pa, best, solids, wb, wa, stats, tolerance);
}

constexpr int kKinds = kShapeKinds;

struct Table {
  CollideFn collide[kKinds][kKinds];
  DistanceFn distance[kKinds][kKinds];
};

Table make_table() {
  Table t{};
  const int mesh = static_cast<int>(ShapeKind::kMesh), sphere = static_cast<int>(ShapeKind::kSphere);
  for (int a = 0; a < kKinds; ++a) {
    for (int b = 0; b < kKinds; ++b) {
      t.collide[a][b] = primitives_collide;
      t.distance[a][b] = primitives_distance;
    }
  }
  for (int a = 0; a < mesh; ++a) {
    t.collide[mesh][a] = mesh_primitive_collide;
    t.distance[mesh][a] = mesh_primitive_distance;
    t.collide[a][mesh] = swapped_collide<mesh_primitive_collide>;
    t.distance[a][mesh] = swapped_distance<mesh_primitive_distance>;
  }
  t.collide[sphere][sphere] = sphere_sphere_collide;
  t.distance[sphere][sphere] = sphere_sphere_distance;
  t.collide[sphere][mesh] = sphere_mesh_collide;
  t.distance[sphere][mesh] = sphere_mesh_distance;
  t.collide[mesh][sphere] = swapped_collide<sphere_mesh_collide>;
  t.distance[mesh][sphere] = swapped_distance<sphere_mesh_distance>;
  t.collide[mesh][mesh] = meshes_collide;
  t.distance[mesh][mesh] = meshes_distance;
  return t;
}

const Table& table() {
  static const Table t = make_table();
  return t;
}

}  // namespace


bool shapes_collide(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                    const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  return table().collide[static_cast<int>(kind_of(a))][static_cast<int>(kind_of(b))](a, pa, b, pb, request, contacts,
                                                                                     stats);
}

double shapes_distance(const ShapeRef& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double best,
                       bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  return table().distance[static_cast<int>(kind_of(a))][static_cast<int>(kind_of(b))](a, pa, b, pb, best, solids, wa,
                                                                                      wb, stats, tolerance);
}

}  // namespace bvh_collision
