// Exact primitives (geometry/primitives.h) and the certified convex distance between them and
// meshes (geometry/convex_distance.h, bvh/primitive_queries.h), against independent oracles:
//  - sampling with a proven bound: the cylinder's surface is sampled so that every surface point
//    lies within `delta` of a sample; the distance from a sample to the other shape is a closed
//    form (box, sphere, cylinder) or brute force over triangles, so the true distance lies in
//    [min - delta, min] (a convex distance is 1-Lipschitz and, for disjoint sets, attained on the
//    surface);
//  - constructed contacts whose gaps are exact in doubles: touching (gap 0) and just apart, at
//    scales 1 mm to 100 m and offsets to 1e4 m.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>
#include <string>

#include "bvh_collision/bvh/primitive_queries.h"
#include "bvh_collision/geometry/convex_distance.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(29);
  return r;
}

// ---------------------------------------------------------------- closed-form point distances

double point_box(const Vec3& half, const Vec3& q) { return (q.cwiseAbs() - half).cwiseMax(0.0).norm(); }
double point_cylinder(double r, double h, const Vec3& q) {
  return std::hypot(std::max(0.0, std::hypot(q.x(), q.y()) - r), std::max(0.0, std::abs(q.z()) - h));
}

// A cone (base radius r at z = -h, tip at +h) in the half plane (rho, z): the distance to the
// triangle (0, -h), (r, -h), (0, h), by its two outer edges (0 inside).
double point_cone(double r, double h, const Vec3& q) {
  const double rho = std::hypot(q.x(), q.y()), z = q.z();
  if (std::abs(z) <= h && rho <= r * (h - z) / (2 * h)) return 0.0;
  auto segment = [&](double ax, double az, double bx, double bz) {
    const double ex = bx - ax, ez = bz - az;
    const double t = std::max(0.0, std::min(1.0, ((rho - ax) * ex + (z - az) * ez) / (ex * ex + ez * ez)));
    return std::hypot(rho - (ax + t * ex), z - (az + t * ez));
  };
  return std::min(segment(0, -h, r, -h), segment(r, -h, 0, h));
}

// The distance from p (world) to a placed primitive, by closed form.
double point_primitive(const Primitive& prim, const Transform& pose, const Vec3& p) {
  const Vec3 q = pose.inverse() * p;
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return std::max(0.0, q.norm() - prim.radius);
    case Primitive::Kind::kBox: return point_box(prim.half, q);
    case Primitive::Kind::kCylinder: return point_cylinder(prim.radius, prim.half_length, q);
    case Primitive::Kind::kCapsule: {
      const double z = std::max(-prim.half_length, std::min(prim.half_length, q.z()));
      return std::max(0.0, (q - Vec3(0, 0, z)).norm() - prim.radius);
    }
    case Primitive::Kind::kCone: return point_cone(prim.radius, prim.half_length, q);
  }
  return NAN;
}

// Points on a cylinder's surface (world) such that every surface point is within `delta` of one.
struct Samples {
  std::vector<Vec3> points;
  double delta = 0.0;
};
Samples cylinder_surface(double r, double h, const Transform& pose, int around, int along) {
  Samples s;
  const double dtheta = 2 * M_PI / around, dz = 2 * h / along;
  // Side: a point lies within half a step of arc and of height from the nearest grid point.
  s.delta = 0.5 * std::hypot(r * dtheta, dz);
  for (int i = 0; i < around; ++i) {
    const double t = i * dtheta;
    for (int k = 0; k <= along; ++k) s.points.push_back(pose * Vec3(r * std::cos(t), r * std::sin(t), -h + k * dz));
  }
  // Caps: rings every dz-sized radial step, each with `around` points (arc steps at most r dtheta).
  const int rings = std::max(1, static_cast<int>(std::ceil(r / dz)));
  for (int ring = 0; ring <= rings; ++ring) {
    const double rho = r * ring / rings;
    for (int i = 0; i < around; ++i) {
      const double t = i * dtheta;
      for (const double z : {-h, h}) s.points.push_back(pose * Vec3(rho * std::cos(t), rho * std::sin(t), z));
    }
  }
  s.delta = std::max(s.delta, 0.5 * std::hypot(r * dtheta, r / rings));
  return s;
}

// The same for a cone's surface: its side by angle and by steps along the generators (a point
// lies within half an arc step and half a generator step of a grid point: their sum bounds the
// distance), its base by rings as a cylinder's cap.
Samples cone_surface(double r, double h, const Transform& pose, int around, int along) {
  Samples s;
  const double dtheta = 2 * M_PI / around, generator = std::hypot(r, 2 * h);
  for (int i = 0; i < around; ++i) {
    const double t = i * dtheta;
    for (int k = 0; k <= along; ++k) {
      const double f = static_cast<double>(k) / along;  // 0 at the rim, 1 at the tip
      s.points.push_back(pose * Vec3((1 - f) * r * std::cos(t), (1 - f) * r * std::sin(t), -h + 2 * h * f));
    }
  }
  const int rings = std::max(1, static_cast<int>(std::ceil(r / (generator / along))));
  for (int ring = 0; ring <= rings; ++ring) {
    const double rho = r * ring / rings;
    for (int i = 0; i < around; ++i) s.points.push_back(pose * Vec3(rho * std::cos(i * dtheta), rho * std::sin(i * dtheta), -h));
  }
  s.delta = std::max(0.5 * (r * dtheta + generator / along), 0.5 * (r * dtheta + r / rings));
  return s;
}

// ---------------------------------------------------------------- the primitives themselves

TEST(Primitives, SupportClosestPointContainmentAndRaysAgainstSampling) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Primitive shapes[] = {Primitive::sphere(0.3), Primitive::box(Vec3(0.2, 0.5, 0.9)),
                              Primitive::cylinder(0.25, 0.8), Primitive::capsule(0.15, 0.6),
                              Primitive::cone(0.35, 0.9), Primitive::cone(0.5, 0.1)};
  for (const Primitive& p : shapes) {
    for (int i = 0; i < 300; ++i) {
      const Vec3 d(u(rng()), u(rng()), u(rng()));
      // The support point is in the primitive and no sampled point of it goes farther along d.
      const Vec3 s = support(p, d);
      EXPECT_LE(point_primitive(p, Transform::Identity(), s), 1e-12) << primitive_name(p.kind);
      const Vec3 probe = s + 1e-9 * d.normalized();
      EXPECT_GT(point_primitive(p, Transform::Identity(), probe), 0.0) << "support on the surface";
      // Closest point: in the primitive, at the closed-form distance.
      const Vec3 q = 1.5 * Vec3(u(rng()), u(rng()), u(rng()));
      const Vec3 c = closest_point(p, q);
      const double want = point_primitive(p, Transform::Identity(), q);
      EXPECT_NEAR((c - q).norm(), want, 1e-12) << primitive_name(p.kind);
      EXPECT_EQ(contains(p, q), want == 0.0) << primitive_name(p.kind);
      // Ray entry: the first point at distance 0, found by bisection after a fine march.
      const Vec3 unit = d.normalized();
      const Vec3 origin = q - unit;
      double first = std::numeric_limits<double>::infinity();
      for (int k = 0; k <= 4000; ++k) {
        if (point_primitive(p, Transform::Identity(), origin + unit * (k * 1e-3)) == 0.0) {
          double lo = std::max(0.0, (k - 1) * 1e-3), hi = k * 1e-3;
          for (int b = 0; b < 60 && k > 0; ++b) {
            const double mid = 0.5 * (lo + hi);
            (point_primitive(p, Transform::Identity(), origin + unit * mid) == 0.0 ? hi : lo) = mid;
          }
          first = hi;
          break;
        }
      }
      const double got = ray_entry(p, origin, unit, 4.0);
      if (std::isfinite(first)) {
        EXPECT_NEAR(got, first, 1e-9) << primitive_name(p.kind);
      } else {
        // The march misses only rays that graze within its step.
        EXPECT_TRUE(!std::isfinite(got) || point_primitive(p, Transform::Identity(), origin + got * unit) <= 1e-9);
      }
    }
  }
}

// ------------------------------------------- cylinder against other shapes: sampled intervals

struct Other {
  const char* name;
  Primitive primitive;             // when mesh is empty
  TriangleMesh mesh;               // brute force over its triangles
};

double other_distance(const Other& o, const Transform& pose, const Vec3& p) {
  if (o.mesh.empty()) return point_primitive(o.primitive, pose, p);
  const Vec3 q = pose.inverse() * p;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t t = 0; t < o.mesh.triangles.size(); ++t) {
    const Triangle tri = o.mesh.triangle(t);
    best = std::min(best, (closest_point_on_triangle(q, tri[0], tri[1], tri[2]) - q).norm());
  }
  return best;
}

// `shape` (a cylinder or a cone, radius r, half length h) against a box, a sphere, a cylinder, a
// cone and a mesh: our distance within the sampled interval, and no contact missed.
void against_others_within_the_sampled_interval(const Primitive& shape) {
  const double r = shape.radius, h = shape.half_length;
  const Other others[] = {
      {"box", Primitive::box(Vec3(0.3, 0.15, 0.2)), {}},
      {"sphere", Primitive::sphere(0.12), {}},
      {"cylinder", Primitive::cylinder(0.08, 0.5), {}},
      {"cone", Primitive::cone(0.12, 0.3), {}},
      {"mesh", {}, test::bumpy_sphere(rng(), 0.15, 6, 8, 0.15)},
  };
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (const Other& o : others) {
    const Bvh<Obb> bvh = o.mesh.empty() ? Bvh<Obb>() : Bvh<Obb>::build(o.mesh);
    int decided = 0;
    for (int i = 0; i < test::sized(24); ++i) {
      const Transform pa = test::random_rotation(rng(), Vec3(u(rng()), u(rng()), u(rng())) * 0.1);
      const Transform pb = test::random_rotation(rng(), pa.t + Vec3(u(rng()), u(rng()), u(rng())) * 0.35);
      // Under the sanitizers a coarser grid (a wider interval, the same checks): its 28,800 exact
      // distances a placement were most of the sanitized pass's two slowest cases.
      const int around = test::sanitized() ? 120 : 240, along = test::sanitized() ? 60 : 120;
      const Samples s = shape.kind == Primitive::Kind::kCone ? cone_surface(r, h, pa, around, along)
                                                              : cylinder_surface(r, h, pa, around, along);
      double sampled = std::numeric_limits<double>::infinity();
      for (const Vec3& p : s.points) sampled = std::min(sampled, other_distance(o, pb, p));
      // The truth: in [sampled - delta, sampled] when the sets are apart (a point of the cylinder
      // inside the other shape shows contact: sampled 0).
      double ours;
      bool collides;
      if (o.mesh.empty()) {
        const ConvexDistance d = convex_distance(ConvexShape::of(shape), ConvexShape::of(o.primitive),
                                                 relative_transform(pa, pb));
        ours = d.distance;
        collides = convex_within(ConvexShape::of(shape), ConvexShape::of(o.primitive), relative_transform(pa, pb), 0.0);
        EXPECT_LE(d.lower_bound, d.distance);
      } else {
        ours = distance(bvh, pb, shape, pa).distance;
        CollisionRequest c;
        c.solids = false;  // the sampled oracle sees the mesh's surface only
        collides = collide(bvh, pb, shape, pa, c).collision;
      }
      if (sampled > s.delta) {
        ++decided;
        EXPECT_FALSE(collides) << primitive_name(shape.kind) << " and " << o.name << " " << i;
        EXPECT_GE(ours, sampled - s.delta - 1e-12) << primitive_name(shape.kind) << " and " << o.name << " " << i;
        EXPECT_LE(ours, sampled + 1e-12) << primitive_name(shape.kind) << " and " << o.name << " " << i;
      } else if (sampled == 0.0 && o.mesh.empty()) {
        EXPECT_TRUE(collides) << primitive_name(shape.kind) << " and " << o.name << " " << i;
        EXPECT_EQ(ours, 0.0) << primitive_name(shape.kind) << " and " << o.name << " " << i;
      }
    }
    // At least a third of the placements are apart by more than the sampling's bound (the
    // others test only that no contact is missed); one of the sanitizers' six.
    EXPECT_GE(decided, test::sanitized() ? 1 : 24 / 3) << primitive_name(shape.kind) << " and " << o.name;
  }
}

TEST(Primitives, CylinderAgainstBoxSphereCylinderAndMeshWithinTheSampledInterval) {
  against_others_within_the_sampled_interval(Primitive::cylinder(0.1, 0.4));
}

TEST(Primitives, ConeAgainstBoxSphereCylinderConeAndMeshWithinTheSampledInterval) {
  against_others_within_the_sampled_interval(Primitive::cone(0.12, 0.4));
}

// ------------------------------------------------ a mesh's boolean hit

// A boolean mesh-primitive test ends at the first triangle with a corner inside the primitive,
// with no convex distance; asked for a contact it takes the convex distance of every triangle.
// Both answer alike over a bumpy sphere against every primitive, from deep inside to apart, with
// and without padding; the sampled-interval tests above check the latter against the geometry.
TEST(MeshAgainstPrimitive, ABooleanHitAnswersAsTheConvexDistances) {
  const TriangleMesh mesh = test::bumpy_sphere(rng(), 0.1, 8, 12, 0.3);
  const Bvh<Obb> bvh = Bvh<Obb>::build(mesh);
  const Primitive shapes[] = {Primitive::box(Vec3(0.1, 0.06, 0.04)), Primitive::sphere(0.05), Primitive::cylinder(0.04, 0.2),
                              Primitive::capsule(0.03, 0.1), Primitive::cone(0.06, 0.12)};
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0, misses = 0;
  for (int i = 0; i < test::sized(2000); ++i) {
    const Primitive& p = shapes[i % 5];
    const Transform pose = test::random_rotation(rng(), Vec3(u(rng()), u(rng()), u(rng())) * 0.2);
    for (const double padding : {0.0, 0.01}) {
      CollisionRequest boolean;
      boolean.padding = padding;
      CollisionRequest contact = boolean;
      contact.max_contacts = 1;
      const bool hit = collide(bvh, Transform::Identity(), p, pose, boolean).collision;
      EXPECT_EQ(hit, collide(bvh, Transform::Identity(), p, pose, contact).collision) << i << " padding " << padding;
      (hit ? hits : misses) += 1;
    }
  }
  EXPECT_GT(hits, test::sized(2000) / 4);
  EXPECT_GT(misses, test::sized(2000) / 4);
}

// ------------------------------------------------ distances within a slack

// The distance from p (world) to a triangle (world).
double point_triangle(const Triangle& t, const Vec3& p) { return (closest_point_on_triangle(p, t[0], t[1], t[2]) - p).norm(); }

// A distance asked within a slack (convex_distance's `slack`; a mesh's DistanceRequest::tolerance)
// may stop early, and what it reports still holds: the bound never exceeds the distance asked to
// the last digit (whose witnesses are two points of the sets: the truth is at most that), it is
// within the slack of it, and the reported distance is that of two points of the sets. Curved
// primitives against a triangle, a hull and one another, 0.1 mm to 5 cm apart, where exact
// GJK creeps towards the curved surface and the certified bound needs a search of directions:
// within 10 um it asks under half the support points.
TEST(ConvexDistance, ASlackStopsWithinItAndTheBoundStillHolds) {
  const Primitive curved[] = {Primitive::cylinder(0.08, 0.3), Primitive::cone(0.12, 0.3), Primitive::capsule(0.05, 0.2),
                              Primitive::sphere(0.1)};
  std::uniform_real_distribution<double> u(-1.0, 1.0), gap_exponent(-4.0, std::log10(0.05));
  const TriangleMesh bumpy = test::bumpy_sphere(rng(), 0.12, 6, 8, 0.2);
  const ConvexHull hull = convex_hull(bumpy.vertices);
  const Bvh<Obb> bvh = Bvh<Obb>::build(bumpy);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  long exact_queries = 0, loose_queries = 0;
  int cases = 0;
  for (int i = 0; i < test::sized(600); ++i) {
    const Primitive& a = curved[i % 4];
    const Triangle tri{Vec3(u(rng()), u(rng()), u(rng())) * 0.2, Vec3(u(rng()), u(rng()), u(rng())) * 0.2,
                       Vec3(u(rng()), u(rng()), u(rng())) * 0.2};
    const int kind = (i / 4) % 3;  // a triangle, a hull, another curved primitive
    const ConvexShape b = kind == 0 ? ConvexShape::of(tri) : kind == 1 ? ConvexShape::of(hull) : ConvexShape::of(curved[(i / 12) % 4]);
    // Placed along a random direction at a chosen gap: b's pose moved until the exact distance
    // is about that gap (one correction along the witnesses' line).
    Transform b_in_a = test::random_rotation(rng(), Vec3(u(rng()), u(rng()), u(rng())).normalized() * 0.6);
    ConvexDistance exact = convex_distance(ConvexShape::of(a), b, b_in_a);
    if (exact.intersecting) continue;
    const double gap = std::pow(10.0, gap_exponent(rng()));
    b_in_a.t += (exact.on_a - exact.on_b).normalized() * (exact.distance - gap);
    exact = convex_distance(ConvexShape::of(a), b, b_in_a);
    if (exact.intersecting) continue;
    ++cases;
    exact_queries += exact.support_queries;
    const double scale = extent(ConvexShape::of(a)) + extent(b) + b_in_a.t.norm();
    for (const double slack : {1e-6, 1e-5, 1e-4}) {
      const ConvexDistance loose = convex_distance(ConvexShape::of(a), b, b_in_a, nan, slack);
      if (slack == 1e-5) loose_queries += loose.support_queries;
      const std::string where = "case " + std::to_string(i) + " slack " + std::to_string(slack);
      EXPECT_LE(loose.lower_bound, exact.distance + 1e-14 * scale) << where;
      EXPECT_GE(loose.lower_bound, exact.lower_bound - slack - 1e-14 * scale) << where;
      EXPECT_GE(loose.distance, exact.lower_bound - 1e-14 * scale) << where;
      EXPECT_LE(loose.distance, exact.distance + slack + 1e-14 * scale) << where;
      // The witnesses are points of the sets (a's in its frame, b's placed by b_in_a).
      EXPECT_LE(point_primitive(a, Transform::Identity(), loose.on_a), 1e-12) << where;
      if (kind == 0) {
        EXPECT_LE(point_triangle(tri, b_in_a.inverse() * loose.on_b), 1e-12) << where;
      } else if (kind == 2) {
        EXPECT_LE(point_primitive(b.primitive, b_in_a, loose.on_b), 1e-12) << where;
      }
    }
  }
  EXPECT_GE(cases, test::sized(600) / 2);
  EXPECT_LT(2 * loose_queries, exact_queries) << loose_queries << " support points within 10 um against " << exact_queries;
  std::cout << cases << " placements: " << exact_queries << " support points exact, " << loose_queries << " within 10 um\n";
  // The mesh through its BVH at a tolerance: at most the tolerance above its exact distance,
  // never below it, each triangle asked within the tolerance.
  for (int i = 0; i < test::sized(60); ++i) {
    const Primitive& a = curved[i % 4];
    const Transform pa = test::random_rotation(rng(), Vec3(u(rng()), u(rng()), u(rng())).normalized() * (0.3 + 0.05 * std::abs(u(rng()))));
    const double exact = distance(bvh, Transform::Identity(), a, pa).distance;
    DistanceRequest request;
    request.tolerance = 1e-4;
    const double loose = distance(bvh, Transform::Identity(), a, pa, request).distance;
    EXPECT_GE(loose, exact - 1e-9 * exact - 1e-12) << i;  // (the exact one is certified to 1e-9 of itself)
    EXPECT_LE(loose, exact + request.tolerance + 1e-12) << i;
  }
}

// ------------------------------------------------ constructed contacts, scales and offsets

// Two placed shapes touching (gap 0) along x, then moved `gap` apart; every coordinate is a
// dyadic multiple of the scale, so the placements are exact in doubles.
struct Contact {
  const char* name;
  Primitive b;
  Transform b_pose;  // at gap 0, the cylinder (radius s/4, length s) at the origin
  int axis;          // the shapes move apart along this axis
};

TEST(Primitives, TouchingCollidesAndJustApartIsFreeAtEveryScaleAndOffset) {
  for (const double scale : {0.0009765625, 0.0625, 1.0, 128.0}) {  // 1 mm to 100 m, powers of two
    for (const double offset : {0.0, 1e4}) {
      const double r = scale / 4, h = scale / 2;
      const Primitive cylinder = Primitive::cylinder(r, 2 * h);
      const Mat3 x_axis = Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()).toRotationMatrix();
      const Contact contacts[] = {
          {"side by side", Primitive::cylinder(r, 2 * h), Transform::Translation(Vec3(2 * r, 0, 0)), 0},
          {"end to end", Primitive::cylinder(r, 2 * h), Transform::Translation(Vec3(0, 0, 2 * h)), 2},
          {"box face on side", Primitive::box(Vec3(scale, scale, scale)), Transform::Translation(Vec3(r + scale / 2, 0, 0)), 0},
          {"box face on cap", Primitive::box(Vec3(scale, scale, scale)), Transform::Translation(Vec3(0, 0, h + scale / 2)), 2},
          {"sphere on side", Primitive::sphere(r), Transform::Translation(Vec3(2 * r, 0, 0)), 0},
          {"capsule on side", Primitive::capsule(r, 2 * h), Transform::Translation(Vec3(2 * r, 0, 0)), 0},
          // A cylinder along x: its cap (a disc) against the side, exact only when the quarter
          // turn's rounding (6e-17 rad) moves nothing by more than the gaps tested.
          {"cap on side", Primitive::cylinder(r, 2 * h), {x_axis, Vec3(r + h, 0, 0)}, 0},
      };
      const Vec3 shift = Vec3::Constant(offset);
      // The smallest gap the placement can hold: a few units in the last place of the offset.
      const double ulp = offset > 0 ? std::nextafter(offset, 2 * offset) - offset : 0.0;
      const double small = std::max(1e-12 * scale, 8 * ulp);
      for (const Contact& c : contacts) {
        for (const double nominal : {0.0, small, 1e-6 * scale}) {
          const Transform pa = Transform::Translation(shift);
          Transform pb = c.b_pose;
          pb.t = pb.t + shift + nominal * Vec3::Unit(c.axis);
          const Transform rel = relative_transform(pa, pb);
          // The gap as placed: the offset's rounding moves it by up to half a unit in its last
          // place (the subtractions here are exact).
          const double gap = rel.t[c.axis] - c.b_pose.t[c.axis];
          const ConvexDistance d = convex_distance(ConvexShape::of(cylinder), ConvexShape::of(c.b), rel);
          const bool collides = convex_within(ConvexShape::of(cylinder), ConvexShape::of(c.b), rel, 0.0);
          const std::string what = std::string(c.name) + " scale " + std::to_string(scale) + " offset " +
                                   std::to_string(offset) + " gap " + std::to_string(gap / scale) + " x scale";
          EXPECT_EQ(collides, gap <= 0.0) << what;
          EXPECT_LE(d.lower_bound, gap + 1e-15 * scale) << what;
          // Witnesses on curved surfaces come within 1e-10 of the scale; the decision is exact.
          EXPECT_NEAR(d.distance, std::max(0.0, gap), 1e-10 * scale + 1e-9 * gap) << what;
        }
      }
    }
  }
}

// A cone (base radius s/4, length s: base at z = -s/2, tip at +s/2) touching other shapes at its
// tip, its rim and its base, then moved apart along `away`: every placement is exact in doubles
// (dyadic sizes; the half turn about x is an exact matrix).
TEST(Primitives, ConeTouchingCollidesAndJustApartIsFreeAtEveryScaleAndOffset) {
  struct ConeContact {
    const char* name;
    Primitive b;
    Transform b_pose;
    Vec3 away;  // a unit axis
  };
  Mat3 flip = Mat3::Identity();
  flip(1, 1) = flip(2, 2) = -1.0;  // a half turn about x: the tip down
  for (const double scale : {0.0009765625, 0.0625, 1.0, 128.0}) {
    for (const double offset : {0.0, 1e4}) {
      const double r = scale / 4, h = scale / 2;
      const Primitive cone = Primitive::cone(r, 2 * h);
      const ConeContact contacts[] = {
          {"tip on box face", Primitive::box(Vec3(scale, scale, scale)), Transform::Translation(Vec3(0, 0, h + scale / 2)), Vec3::UnitZ()},
          {"base on box face", Primitive::box(Vec3(scale, scale, scale)), Transform::Translation(Vec3(0, 0, -h - scale / 2)), -Vec3::UnitZ()},
          {"rim on box face", Primitive::box(Vec3(scale, scale, scale)), Transform::Translation(Vec3(r + scale / 2, 0, -h)), Vec3::UnitX()},
          {"tip on sphere", Primitive::sphere(r), Transform::Translation(Vec3(0, 0, h + r)), Vec3::UnitZ()},
          {"base on sphere", Primitive::sphere(r), Transform::Translation(Vec3(0, 0, -h - r)), -Vec3::UnitZ()},
          {"base on cylinder end", Primitive::cylinder(r, 2 * h), Transform::Translation(Vec3(0, 0, -2 * h)), -Vec3::UnitZ()},
          {"rim on cylinder side", Primitive::cylinder(r, 2 * h), Transform::Translation(Vec3(2 * r, 0, -2 * h)), Vec3::UnitX()},
          {"base to base", Primitive::cone(r, 2 * h), {flip, Vec3(0, 0, -2 * h)}, -Vec3::UnitZ()},
          {"tip to tip", Primitive::cone(r, 2 * h), {flip, Vec3(0, 0, 2 * h)}, Vec3::UnitZ()},
      };
      const Vec3 shift = Vec3::Constant(offset);
      const double ulp = offset > 0 ? std::nextafter(offset, 2 * offset) - offset : 0.0;
      const double small = std::max(1e-12 * scale, 8 * ulp);
      for (const ConeContact& c : contacts) {
        for (const double nominal : {0.0, small, 1e-6 * scale}) {
          const Transform pa = Transform::Translation(shift);
          Transform pb = c.b_pose;
          pb.t = pb.t + shift + nominal * c.away;
          const Transform rel = relative_transform(pa, pb);
          const double gap = (rel.t - c.b_pose.t).dot(c.away);  // exact: one coordinate
          const ConvexDistance d = convex_distance(ConvexShape::of(cone), ConvexShape::of(c.b), rel);
          const bool collides = convex_within(ConvexShape::of(cone), ConvexShape::of(c.b), rel, 0.0);
          const std::string what = std::string(c.name) + " scale " + std::to_string(scale) + " offset " +
                                   std::to_string(offset) + " gap " + std::to_string(gap / scale) + " x scale";
          EXPECT_EQ(collides, gap <= 0.0) << what;
          EXPECT_LE(d.lower_bound, gap + 1e-15 * scale) << what;
          EXPECT_NEAR(d.distance, std::max(0.0, gap), 1e-10 * scale + 1e-9 * gap) << what;
          // The swapped pair decides alike.
          EXPECT_EQ(convex_within(ConvexShape::of(c.b), ConvexShape::of(cone), rel.inverse(), 0.0), gap <= 0.0) << what;
        }
      }
    }
  }
}

// A cone against a mesh face: its rim on the plane x = r, its tip on the plane z = h.
TEST(Primitives, ConeTouchingAMeshFace) {
  for (const double scale : {0.0009765625, 1.0, 128.0}) {
    const double r = scale / 4, h = scale / 2;
    const Primitive cone = Primitive::cone(r, 2 * h);
    TriangleMesh wall;  // in the plane x = 0, centred on z = -h (the rim's height)
    wall.vertices = {Vec3(0, -scale, -h - scale), Vec3(0, scale, -h - scale), Vec3(0, scale, -h + scale), Vec3(0, -scale, -h + scale)};
    wall.triangles = {{0, 1, 2}, {0, 2, 3}};
    TriangleMesh ceiling;  // in the plane z = 0
    ceiling.vertices = {Vec3(-scale, -scale, 0), Vec3(scale, -scale, 0), Vec3(scale, scale, 0), Vec3(-scale, scale, 0)};
    ceiling.triangles = {{0, 1, 2}, {0, 2, 3}};
    const Bvh<Obb> wall_bvh = Bvh<Obb>::build(wall), ceiling_bvh = Bvh<Obb>::build(ceiling);
    for (const double gap : {0.0, 1e-12 * scale, 1e-6 * scale}) {
      const Transform wall_pose = Transform::Translation(Vec3(r + gap, 0, 0));
      EXPECT_EQ(collide(wall_bvh, wall_pose, cone, Transform::Identity()).collision, gap == 0.0) << scale << " " << gap;
      EXPECT_NEAR(distance(wall_bvh, wall_pose, cone, Transform::Identity()).distance, gap, 1e-12 * scale) << scale;
      const Transform ceiling_pose = Transform::Translation(Vec3(0, 0, h + gap));
      EXPECT_EQ(collide(ceiling_bvh, ceiling_pose, cone, Transform::Identity()).collision, gap == 0.0) << scale << " " << gap;
      EXPECT_NEAR(distance(ceiling_bvh, ceiling_pose, cone, Transform::Identity()).distance, gap, 1e-12 * scale) << scale;
    }
  }
}

// A cylinder against a mesh face (two triangles in the plane x = r): touching and 1e-12 apart.
TEST(Primitives, CylinderTouchingAMeshFace) {
  for (const double scale : {0.0009765625, 1.0, 128.0}) {
    const double r = scale / 4;
    TriangleMesh wall;
    wall.vertices = {Vec3(0, -scale, -scale), Vec3(0, scale, -scale), Vec3(0, scale, scale), Vec3(0, -scale, scale)};
    wall.triangles = {{0, 1, 2}, {0, 2, 3}};
    const Bvh<Obb> bvh = Bvh<Obb>::build(wall);
    const Primitive cylinder = Primitive::cylinder(r, scale);
    for (const double gap : {0.0, 1e-12 * scale, 1e-6 * scale}) {
      const Transform wall_pose = Transform::Translation(Vec3(r + gap, 0, 0));
      EXPECT_EQ(collide(bvh, wall_pose, cylinder, Transform::Identity()).collision, gap == 0.0) << scale << " " << gap;
      EXPECT_NEAR(distance(bvh, wall_pose, cylinder, Transform::Identity()).distance, gap, 1e-12 * scale) << scale;
    }
  }
}

}  // namespace
}  // namespace bvh_collision
