// A body made of several shapes (a link's collision elements, with what it carries): the compound
// the queries take, so "does any shape of the link ..." and "the nearest shape of the link" are
// written once, here, for every counterpart: a shape, another compound, the octree, a point, a ray.
// The owner keeps the parts in a compact form (a mesh index or an exact primitive) beside its
// tables of meshes and hulls; a CompoundShape is a view of them.
#pragma once

#include <vector>

#include "bvh_collision/narrowphase/shape_octree.h"
#include "bvh_collision/narrowphase/shape_pairs.h"

namespace bvh_collision {

// One part of a compound, in the compound's frame.
struct CompoundPart {
  Transform origin;
  int mesh = -1;  // index into the owner's meshes and hulls, or -1 for `primitive`
  Primitive primitive;
};

class CompoundShape {
 public:
  CompoundShape(const std::vector<CompoundPart>& parts, const std::vector<Bvh<Obb>>& meshes,
                const std::vector<ConvexHull>& hulls)
      : parts_(&parts), meshes_(&meshes), hulls_(&hulls) {}

  std::size_t size() const { return parts_->size(); }
  const CompoundPart& part(std::size_t i) const { return (*parts_)[i]; }
  ShapeRef ref(std::size_t i) const { return shape_ref(*meshes_, *hulls_, part(i).mesh, part(i).primitive); }

 private:
  const std::vector<CompoundPart>* parts_;
  const std::vector<Bvh<Obb>>* meshes_;
  const std::vector<ConvexHull>* hulls_;
};

// Does any part of `a` collide with `b` (shapes_collide's semantics, part by part)? Contacts are
// appended to `contacts` (when not null) up to request.max_contacts in all; the walk stops at the
// first hit once no more contacts are wanted.
bool compound_collides(const CompoundShape& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                       const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats);
bool compounds_collide(const CompoundShape& a, const Transform& pa, const CompoundShape& b, const Transform& pb,
                       const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats);

// The distance between the nearest parts when below `best` (else `best` or more), witnesses as
// shapes_distance gives them (set only when a pair comes below `best`).
double compound_distance(const CompoundShape& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double best,
                         bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance = 0.0);
double compounds_distance(const CompoundShape& a, const Transform& pa, const CompoundShape& b, const Transform& pb,
                          double best, bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance = 0.0);

// The octree as the counterpart: any part within request.padding of an occupied cube (the first
// such part's contact), and the nearest occupied cube below `upper_bound`.
bool compound_meets_octree(const CompoundShape& a, const Transform& pa, const Octree& tree, const PairRequest& request,
                           OctreeContact* contact, QueryStats& stats);
OctreeDistance compound_octree_distance(const CompoundShape& a, const Transform& pa, const Octree& tree, bool solids,
                                        double upper_bound, QueryStats& stats);

// A point on or within `padding` of some part; the first entry of a ray into any part (at most
// `length`; infinity when it enters none).
bool compound_holds_point(const CompoundShape& a, const Transform& pa, const Vec3& p, double padding);
double compound_ray_entry(const CompoundShape& a, const Transform& pa, const Vec3& origin, const Vec3& unit, double length);

}  // namespace bvh_collision
