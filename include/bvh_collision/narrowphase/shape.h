// The narrowphase's unit: one shape of a body (a link's collision element, a collision object),
// whoever owns its geometry, and the kinds the engine dispatches over. A query takes ShapeRefs and
// dispatches once, here in narrowphase/ (shape_pairs.h for two shapes, shape_octree.h for a shape
// against the octree, shape_queries.h for a point, a ray or a bound); code above this layer never
// tests a shape's kind.
#pragma once

#include <vector>

#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/primitives.h"

namespace bvh_collision {

// One shape's geometry: a mesh (its BVH and hull), or an exact primitive.
struct ShapeRef {
  const Bvh<Obb>* mesh = nullptr;  // null: `primitive`
  const ConvexHull* hull = nullptr;
  Primitive primitive;
};

// The kind the dispatch tables index the shape by (geometry/primitives.h's ShapeKind).
inline ShapeKind kind_of(const ShapeRef& s) { return s.mesh != nullptr ? ShapeKind::kMesh : s.primitive.kind; }

// The shape's exact primitive, or null for a mesh (for accelerators that keep primitives apart).
inline const Primitive* exact_primitive(const ShapeRef& s) { return s.mesh == nullptr ? &s.primitive : nullptr; }

// A shape of a body's list: the mesh `index` names in `meshes` and `hulls` (same indices), or the
// exact primitive when `index` is negative. Inline: link shapes are looked up in every query.
inline ShapeRef shape_ref(const std::vector<Bvh<Obb>>& meshes, const std::vector<ConvexHull>& hulls, int index,
                          const Primitive& primitive) {
  if (index < 0) return ShapeRef{nullptr, nullptr, primitive};
  return ShapeRef{&meshes[static_cast<std::size_t>(index)], &hulls[static_cast<std::size_t>(index)], Primitive{}};
}

// The inverse of shape_ref: `shape` kept in such tables, its hierarchy and hull copied to the
// end of `meshes` and `hulls` (their index returned), or -1 for a primitive (which the caller
// keeps itself).
inline int append_shape(const ShapeRef& shape, std::vector<Bvh<Obb>>& meshes, std::vector<ConvexHull>& hulls) {
  if (shape.mesh == nullptr) return -1;
  meshes.push_back(*shape.mesh);
  hulls.push_back(*shape.hull);
  return static_cast<int>(meshes.size()) - 1;
}

// A shape placed in its body's frame.
struct BodyShape {
  ShapeRef shape;
  Transform origin;  // shape frame -> body frame
};

}  // namespace bvh_collision
