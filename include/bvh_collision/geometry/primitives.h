// Exact convex primitives: the solids URDF and collision objects name (sphere, box, cylinder,
// capsule, cone), kept as the shapes they are instead of polygons. Each lives in its own frame,
// centred on the origin; cylinders, capsules and cones run along z (a cone as shape_msgs has it:
// its bounding box centred on the origin, the base disc at z = -length/2, the tip at +length/2). Everything here is a closed solid: touching
// a primitive's surface is touching the primitive.
#pragma once

#include <cstdint>
#include <limits>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// The kinds of shape, one list for every layer: the exact primitives, and a triangle mesh (a
// link's or an object's, with its hierarchy and hull). The narrowphase's tables are indexed by it.
enum class ShapeKind : std::uint8_t { kSphere, kBox, kCylinder, kCapsule, kCone, kMesh };
constexpr int kShapeKinds = 6;

struct Primitive {
  using Kind = ShapeKind;  // never kMesh
  Kind kind = Kind::kSphere;
  Vec3 half = Vec3::Zero();  // box: half the edge lengths
  double radius = 0.0;       // sphere, cylinder, capsule; cone: of its base
  double half_length = 0.0;  // cylinder, capsule, cone: half the length of the axis segment (z)

  static Primitive sphere(double r) { return {Kind::kSphere, Vec3::Zero(), r, 0.0}; }
  static Primitive box(const Vec3& size) { return {Kind::kBox, 0.5 * size, 0.0, 0.0}; }
  // A capsule's length is that of its axis segment; its caps add `r` at each end (as in FCL).
  static Primitive cylinder(double r, double length) { return {Kind::kCylinder, Vec3::Zero(), r, 0.5 * length}; }
  static Primitive capsule(double r, double length) { return {Kind::kCapsule, Vec3::Zero(), r, 0.5 * length}; }
  static Primitive cone(double r, double length) { return {Kind::kCone, Vec3::Zero(), r, 0.5 * length}; }
};

const char* primitive_name(Primitive::Kind kind);

// A point of the primitive farthest along d (d need not be unit; d = 0 gives some point of it).
Vec3 support(const Primitive& p, const Vec3& d);

// Half extents of the primitive's box in its own frame: the tightest box around it.
Vec3 half_extents(const Primitive& p);

// The largest distance of any point of the primitive from its centre.
double bounding_radius(const Primitive& p);

// Is p (in the primitive's frame) inside or on the primitive?
bool contains(const Primitive& prim, const Vec3& p);

// How deep p (in the primitive's frame) lies inside it: the radius of a ball around p that the
// solid holds (its distance to the surface, exact but for the cone, whose slant is measured to
// the whole line in p's half plane: never more than the true depth); 0 or less outside.
double inscribed_depth(const Primitive& prim, const Vec3& p);

// The point of the primitive (the solid) closest to p, in the primitive's frame: p itself when
// p is inside.
Vec3 closest_point(const Primitive& prim, const Vec3& p);

// Where the ray origin + s * unit (unit length, primitive frame), 0 <= s <= length, first meets
// the primitive: 0 when the origin is inside, infinity when it misses.
double ray_entry(const Primitive& prim, const Vec3& origin, const Vec3& unit, double length);

}  // namespace bvh_collision
