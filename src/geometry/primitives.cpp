#include "bvh_collision/geometry/primitives.h"

#include <algorithm>
#include <cmath>

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

}  // namespace

const char* primitive_name(Primitive::Kind kind) {
  switch (kind) {
    case Primitive::Kind::kSphere: return "sphere";
    case Primitive::Kind::kBox: return "box";
    case Primitive::Kind::kCylinder: return "cylinder";
    case Primitive::Kind::kCapsule: return "capsule";
  }
  return "?";
}

Vec3 support(const Primitive& p, const Vec3& d) {
  switch (p.kind) {
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
  }
  return Vec3::Zero();
}

Vec3 half_extents(const Primitive& p) {
  switch (p.kind) {
    case Primitive::Kind::kSphere: return Vec3::Constant(p.radius);
    case Primitive::Kind::kBox: return p.half;
    case Primitive::Kind::kCylinder: return {p.radius, p.radius, p.half_length};
    case Primitive::Kind::kCapsule: return {p.radius, p.radius, p.half_length + p.radius};
  }
  return Vec3::Zero();
}

double bounding_radius(const Primitive& p) {
  switch (p.kind) {
    case Primitive::Kind::kSphere: return p.radius;
    case Primitive::Kind::kBox: return p.half.norm();
    case Primitive::Kind::kCylinder: return std::hypot(p.radius, p.half_length);
    case Primitive::Kind::kCapsule: return p.half_length + p.radius;
  }
  return 0.0;
}

bool contains(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kSphere: return p.squaredNorm() <= prim.radius * prim.radius;
    case Primitive::Kind::kBox: return (p.cwiseAbs().array() <= prim.half.array()).all();
    case Primitive::Kind::kCylinder:
      return std::abs(p.z()) <= prim.half_length && p.x() * p.x() + p.y() * p.y() <= prim.radius * prim.radius;
    case Primitive::Kind::kCapsule: {
      const Vec3 off(p.x(), p.y(), p.z() - std::clamp(p.z(), -prim.half_length, prim.half_length));
      return off.squaredNorm() <= prim.radius * prim.radius;
    }
  }
  return false;
}

Vec3 closest_point(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kSphere: {
      const double n = p.norm();
      return n <= prim.radius ? p : Vec3(p * (prim.radius / n));
    }
    case Primitive::Kind::kBox: return p.cwiseMax(-prim.half).cwiseMin(prim.half);
    case Primitive::Kind::kCylinder: {
      // The solid is a disc times an interval: project onto each.
      const double z = std::clamp(p.z(), -prim.half_length, prim.half_length);
      const double n = std::hypot(p.x(), p.y());
      const double s = n <= prim.radius ? 1.0 : prim.radius / n;
      return {p.x() * s, p.y() * s, z};
    }
    case Primitive::Kind::kCapsule: {
      const Vec3 axis_point(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      const Vec3 off = p - axis_point;
      const double n = off.norm();
      return n <= prim.radius ? p : Vec3(axis_point + off * (prim.radius / n));
    }
  }
  return p;
}

double ray_entry(const Primitive& prim, const Vec3& origin, const Vec3& unit, double length) {
  switch (prim.kind) {
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
  }
  return kInf;
}

}  // namespace bvh_collision
