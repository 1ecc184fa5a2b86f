#include "bvh_collision/geometry/primitives.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "bvh_collision/geometry/intersection.h"

namespace bvh_collision {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

double sign_or_plus(double x) { return x < 0.0 ? -1.0 : 1.0; }

// The parameters s where origin + s * unit lies in the slab |x_axis| <= half, as [lo, hi].
bool slab(double o, double u, double half, double& lo, double& hi) {
  if (u == 0.0) return std::abs(o) <= half;
  double a = (-half - o) / u, b = (half - o) / u;
  if (a > b) std::swap(a, b);
  lo = std::max(lo, a);
  hi = std::min(hi, b);
  return lo <= hi;
}

// The same for the infinite solid cylinder x^2 + y^2 <= r^2.
bool tube(const Vec3& o, const Vec3& u, double r, double& lo, double& hi) {
  const double a = u.x() * u.x() + u.y() * u.y();
  const double b = o.x() * u.x() + o.y() * u.y();
  const double c = o.x() * o.x() + o.y() * o.y() - r * r;
  if (a == 0.0) return c <= 0.0;
  const double disc = b * b - a * c;
  if (disc < 0.0) return false;
  // The root without cancellation, and the other from the product of the roots.
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  double s0 = q / a, s1 = q != 0.0 ? c / q : s0;
  if (s0 > s1) std::swap(s0, s1);
  lo = std::max(lo, s0);
  hi = std::min(hi, s1);
  return lo <= hi;
}

double cylinder_entry(double r, double h, const Vec3& o, const Vec3& u, double length) {
  double lo = 0.0, hi = length;
  if (!slab(o.z(), u.z(), h, lo, hi) || !tube(o, u, r, lo, hi)) return kInf;
  return lo;
}

// The cone (base radius r at z = -h, tip at z = +h) seen in the half plane (rho, z), rho >= 0:
// the triangle (0, -h), (r, -h), (0, h). Its radius at height z, for |z| <= h.
double cone_radius_at(const Primitive& c, double z) {
  return c.half_length > 0.0 ? c.radius * (c.half_length - z) / (2.0 * c.half_length) : c.radius;
}

// The point of the triangle's base or slant edge nearest (rho, z) (outside it), as (rho, z).
std::pair<double, double> cone_nearest_edge_point(const Primitive& c, double rho, double z) {
  const double r = c.radius, h = c.half_length;
  const double base_rho = std::min(rho, r);
  const double base_d2 = (rho - base_rho) * (rho - base_rho) + (z + h) * (z + h);
  // The slant from (r, -h) to (0, h).
  const double ex = -r, ez = 2.0 * h, len2 = ex * ex + ez * ez;
  const double t = len2 > 0.0 ? std::clamp(((rho - r) * ex + (z + h) * ez) / len2, 0.0, 1.0) : 0.0;
  const double slant_rho = r + t * ex, slant_z = -h + t * ez;
  const double slant_d2 = (rho - slant_rho) * (rho - slant_rho) + (z - slant_z) * (z - slant_z);
  return base_d2 <= slant_d2 ? std::make_pair(base_rho, -h) : std::make_pair(slant_rho, slant_z);
}

Vec3 cone_closest_point(const Primitive& c, const Vec3& p) {
  const double rho = std::hypot(p.x(), p.y());
  const auto [q_rho, q_z] = cone_nearest_edge_point(c, rho, p.z());
  // Around the axis the nearest point keeps p's direction (any direction when p is on the axis).
  if (rho > 0.0) return {p.x() * (q_rho / rho), p.y() * (q_rho / rho), q_z};
  return {q_rho, 0.0, q_z};
}

// Where the ray enters the solid cone. Inside the slab |z| <= h the cone is the set
// x^2 + y^2 <= k^2 (h - z)^2, k = r / 2h (the lower nappe: the upper one starts at the tip), so
// the ray is inside where a quadratic in s is at most 0, within the slab's interval.
double cone_entry(const Primitive& c, const Vec3& o, const Vec3& u, double length) {
  const double h = c.half_length;
  if (!(h > 0.0)) return cylinder_entry(c.radius, 0.0, o, u, length);  // a flat cone: a disc
  double lo = 0.0, hi = length;
  if (!slab(o.z(), u.z(), h, lo, hi)) return kInf;
  const double k = c.radius / (2.0 * h), k2 = k * k, w0 = h - o.z();
  const double a = u.x() * u.x() + u.y() * u.y() - k2 * u.z() * u.z();
  const double b = o.x() * u.x() + o.y() * u.y() + k2 * w0 * u.z();
  const double cc = o.x() * o.x() + o.y() * o.y() - k2 * w0 * w0;
  auto first_from = [&](double s) { return s <= hi ? std::max(lo, s) : kInf; };
  if (a == 0.0) {  // the ray runs parallel to a generator: f(s) = 2 b s + cc
    if (b == 0.0) return cc <= 0.0 ? lo : kInf;
    const double root = -cc / (2.0 * b);
    return b > 0.0 ? (lo <= root ? lo : kInf) : first_from(root);
  }
  const double disc = b * b - a * cc;
  if (disc < 0.0) return a < 0.0 ? lo : kInf;
  const double q = -(b + std::copysign(std::sqrt(disc), b));
  double s0 = q / a, s1 = q != 0.0 ? cc / q : s0;
  if (s0 > s1) std::swap(s0, s1);
  if (a > 0.0) return std::max(lo, s0) <= std::min(hi, s1) ? std::max(lo, s0) : kInf;
  // a < 0: inside before s0 and after s1.
  return lo <= s0 ? lo : first_from(s1);
}

}  // namespace

const char* primitive_name(Primitive::Kind kind) {
  switch (kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return "sphere";
    case Primitive::Kind::kBox: return "box";
    case Primitive::Kind::kCylinder: return "cylinder";
    case Primitive::Kind::kCapsule: return "capsule";
    case Primitive::Kind::kCone: return "cone";
  }
  return "?";
}

Vec3 support(const Primitive& p, const Vec3& d) {
  switch (p.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: {
      const double n = d.norm();
      return n > 0.0 ? Vec3(d * (p.radius / n)) : Vec3(Vec3::Zero());
    }
    case Primitive::Kind::kBox:
      return {sign_or_plus(d.x()) * p.half.x(), sign_or_plus(d.y()) * p.half.y(), sign_or_plus(d.z()) * p.half.z()};
    case Primitive::Kind::kCylinder: {
      const double n = std::hypot(d.x(), d.y());
      const double z = sign_or_plus(d.z()) * p.half_length;
      return n > 0.0 ? Vec3(d.x() * (p.radius / n), d.y() * (p.radius / n), z) : Vec3(0.0, 0.0, z);
    }
    case Primitive::Kind::kCapsule: {
      const double n = d.norm();
      const Vec3 end(0.0, 0.0, sign_or_plus(d.z()) * p.half_length);
      return n > 0.0 ? Vec3(end + d * (p.radius / n)) : end;
    }
    case Primitive::Kind::kCone: {
      // The tip or a point of the base's rim, whichever goes farther along d.
      const double n = std::hypot(d.x(), d.y());
      const Vec3 rim = n > 0.0 ? Vec3(d.x() * (p.radius / n), d.y() * (p.radius / n), -p.half_length)
                               : Vec3(0.0, 0.0, -p.half_length);
      const Vec3 tip(0.0, 0.0, p.half_length);
      return d.dot(tip) >= d.dot(rim) ? tip : rim;
    }
  }
  return Vec3::Zero();
}

Vec3 half_extents(const Primitive& p) {
  switch (p.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return Vec3::Constant(p.radius);
    case Primitive::Kind::kBox: return p.half;
    case Primitive::Kind::kCylinder: return {p.radius, p.radius, p.half_length};
    case Primitive::Kind::kCapsule: return {p.radius, p.radius, p.half_length + p.radius};
    case Primitive::Kind::kCone: return {p.radius, p.radius, p.half_length};
  }
  return Vec3::Zero();
}

double inscribed_depth(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return prim.radius - p.norm();
    case Primitive::Kind::kBox: return (prim.half - p.cwiseAbs()).minCoeff();
    case Primitive::Kind::kCylinder:
      return std::min(prim.radius - p.head<2>().norm(), prim.half_length - std::abs(p.z()));
    case Primitive::Kind::kCapsule: {
      const Vec3 axis(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      return prim.radius - (p - axis).norm();
    }
    case Primitive::Kind::kCone: {
      // The nearer of the base and the slant (its distance in the (rho, z) half plane).
      const double h = prim.half_length, slope = prim.radius / std::max(2.0 * h, 1e-300);
      const double slant = (slope * (h - p.z()) - p.head<2>().norm()) / std::sqrt(1.0 + slope * slope);
      return std::min(p.z() + h, slant);
    }
  }
  return 0.0;
}

double bounding_radius(const Primitive& p) {
  switch (p.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return p.radius;
    case Primitive::Kind::kBox: return p.half.norm();
    case Primitive::Kind::kCylinder: return std::hypot(p.radius, p.half_length);
    case Primitive::Kind::kCapsule: return p.half_length + p.radius;
    case Primitive::Kind::kCone: return std::hypot(p.radius, p.half_length);  // the rim (the tip is nearer)
  }
  return 0.0;
}

bool contains(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return p.squaredNorm() <= prim.radius * prim.radius;
    case Primitive::Kind::kBox: return (p.cwiseAbs().array() <= prim.half.array()).all();
    case Primitive::Kind::kCylinder:
      return std::abs(p.z()) <= prim.half_length && p.x() * p.x() + p.y() * p.y() <= prim.radius * prim.radius;
    case Primitive::Kind::kCapsule: {
      const Vec3 off(p.x(), p.y(), p.z() - std::clamp(p.z(), -prim.half_length, prim.half_length));
      return off.squaredNorm() <= prim.radius * prim.radius;
    }
    case Primitive::Kind::kCone: {
      if (!(std::abs(p.z()) <= prim.half_length)) return false;
      const double r = cone_radius_at(prim, p.z());
      return p.x() * p.x() + p.y() * p.y() <= r * r;
    }
  }
  return false;
}

Vec3 closest_point(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: {
      const double n = p.norm();
      return n <= prim.radius ? p : Vec3(p * (prim.radius / n));
    }
    case Primitive::Kind::kBox: return p.cwiseMax(-prim.half).cwiseMin(prim.half);
    case Primitive::Kind::kCylinder: {
      // The solid is a disc times an interval: project onto each.
      // (sqrt, not hypot: a point inside the disc needs no root, and hypot's care for overflow
      // is costly in a test the object grid makes millions of times a plan.)
      const double z = std::clamp(p.z(), -prim.half_length, prim.half_length);
      const double n2 = p.x() * p.x() + p.y() * p.y();
      if (n2 <= prim.radius * prim.radius) return {p.x(), p.y(), z};
      const double s = prim.radius / std::sqrt(n2);
      return {p.x() * s, p.y() * s, z};
    }
    case Primitive::Kind::kCapsule: {
      const Vec3 axis_point(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      const Vec3 off = p - axis_point;
      const double n = off.norm();
      return n <= prim.radius ? p : Vec3(axis_point + off * (prim.radius / n));
    }
    case Primitive::Kind::kCone: return contains(prim, p) ? p : cone_closest_point(prim, p);
  }
  return p;
}

double ray_entry(const Primitive& prim, const Vec3& origin, const Vec3& unit, double length) {
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return ray_ball_entry(origin, unit, length, Vec3::Zero(), prim.radius);
    case Primitive::Kind::kBox: {
      double lo = 0.0, hi = length;
      for (int i = 0; i < 3; ++i) {
        if (!slab(origin[i], unit[i], prim.half[i], lo, hi)) return kInf;
      }
      return lo;
    }
    case Primitive::Kind::kCylinder: return cylinder_entry(prim.radius, prim.half_length, origin, unit, length);
    case Primitive::Kind::kCapsule: {
      // The union of a cylinder and two balls: the first entry into any of them.
      const Vec3 end(0.0, 0.0, prim.half_length);
      return std::min({cylinder_entry(prim.radius, prim.half_length, origin, unit, length),
                       ray_ball_entry(origin, unit, length, end, prim.radius),
                       ray_ball_entry(origin, unit, length, -end, prim.radius)});
    }
    case Primitive::Kind::kCone: return cone_entry(prim, origin, unit, length);
  }
  return kInf;
}

}  // namespace bvh_collision
