#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/detail/filtered_predicates.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision {
namespace {

double clamp01(double x) { return std::min(1.0, std::max(0.0, x)); }

// Keeps the candidate pair (x on a, y on b) if it is closer than the best so far.
void consider(ClosestPoints& best, double& best_sq, const Vec3& x, const Vec3& y) {
  const double sq = (x - y).squaredNorm();
  if (sq < best_sq) {
    best_sq = sq;
    best.on_a = x;
    best.on_b = y;
  }
}

}  // namespace

Vec3 closest_point_on_segment(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double dd = d.squaredNorm();
  if (dd == 0.0) return a;
  return a + clamp01((p - a).dot(d) / dd) * d;
}

Vec3 closest_point_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  if (nn > 0.0 && std::isfinite(nn)) {
    // Inside the prism over the triangle: the projection onto the plane is the closest point.
    const Vec3 ap = p - a, bp = p - b, cp = p - c;
    const bool inside = (b - a).cross(ap).dot(n) >= 0.0 && (c - b).cross(bp).dot(n) >= 0.0 &&
                        (a - c).cross(cp).dot(n) >= 0.0;
    if (inside) return p - (ap.dot(n) / nn) * n;
  }
  // Otherwise (or for a zero-area triangle) the closest point lies on an edge.
  const Vec3 candidates[3] = {closest_point_on_segment(p, a, b), closest_point_on_segment(p, b, c),
                              closest_point_on_segment(p, c, a)};
  int best = 0;
  double best_sq = (candidates[0] - p).squaredNorm();
  for (int i = 1; i < 3; ++i) {
    const double sq = (candidates[i] - p).squaredNorm();
    if (sq < best_sq) {
      best_sq = sq;
      best = i;
    }
  }
  return candidates[best];
}

bool triangle_plane_beyond(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, double limit) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const Vec3 n = ab.cross(ac);
  const double s = ap.dot(n), nn = n.squaredNorm();
  // The plane's distance is |s| / |n|; its rounding and the closest point's are within a few
  // units of 1e-16 of these sizes, far below the slack.
  const double slack = 1e-9 * (limit + ap.cwiseAbs().sum() + ab.cwiseAbs().sum() + ac.cwiseAbs().sum());
  const double reach = limit + slack;
  return nn > 0.0 && s * s > reach * reach * nn;
}

namespace {

// End points against the other segment, plus the common perpendicular when it falls inside both:
// correct for parallel and nearly parallel segments, where the one-pass formula is not.
ClosestPoints segment_segment_robust(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2) {
  ClosestPoints best;
  double best_sq = std::numeric_limits<double>::infinity();
  // End points against the other segment: these cover parallel segments and every clamped case.
  consider(best, best_sq, p1, closest_point_on_segment(p1, q1, q2));
  consider(best, best_sq, p2, closest_point_on_segment(p2, q1, q2));
  consider(best, best_sq, closest_point_on_segment(q1, p1, p2), q1);
  consider(best, best_sq, closest_point_on_segment(q2, p1, p2), q2);
  // Interior pair: the common perpendicular, from the cross product (whose relative error grows
  // as 1/angle, not 1/angle^2 as the a*e - b*b form does). Only used when both parameters fall
  // strictly inside; then it is the global minimum.
  const Vec3 d1 = p2 - p1, d2 = q2 - q1, r = q1 - p1;
  const Vec3 n = d1.cross(d2);
  const double nn = n.squaredNorm();
  if (nn > 0.0) {
    const double s = r.cross(d2).dot(n) / nn;
    const double t = r.cross(d1).dot(n) / nn;
    if (s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0) {
      const Vec3 x = p1 + s * d1;
      consider(best, best_sq, x, closest_point_on_segment(x, q1, q2));
    }
  }
  best.distance = std::sqrt(best_sq);
  return best;
}

}  // namespace

ClosestPoints segment_segment_distance(const Vec3& p1, const Vec3& p2, const Vec3& q1, const Vec3& q2) {
  // Ericson's one-pass clamped solution; exact for segments that are not nearly parallel
  // (|sin angle| > 1e-2, so the 1/sin^2 error growth of the a*e - b*b form stays below 1e4 ulps
  // of the parameter, and the distance, stationary at an interior minimum, is far better).
  const Vec3 d1 = p2 - p1, d2 = q2 - q1, r = p1 - q1;
  const double a = d1.dot(d1), e = d2.dot(d2);
  if (a == 0.0 || e == 0.0) return segment_segment_robust(p1, p2, q1, q2);
  const double b = d1.dot(d2), c = d1.dot(r), f = d2.dot(r);
  const double denom = a * e - b * b;
  if (denom <= 1e-4 * a * e) return segment_segment_robust(p1, p2, q1, q2);
  double s = clamp01((b * f - c * e) / denom);
  double t = (b * s + f) / e;
  if (t < 0.0) {
    t = 0.0;
    s = clamp01(-c / a);
  } else if (t > 1.0) {
    t = 1.0;
    s = clamp01((b - c) / a);
  }
  ClosestPoints out;
  out.on_a = p1 + s * d1;
  out.on_b = q1 + t * d2;
  out.distance = (out.on_a - out.on_b).norm();
  return out;
}

namespace {

// Vertex p against the face of triangle t (normal n, not normalised): when p projects inside t,
// the projection is a closest-pair candidate; otherwise an edge pair covers it.
void vertex_face(ClosestPoints& best, double& best_sq, const Vec3& p, const Triangle& t, const Vec3& n,
                 bool p_on_a) {
  const double nn = n.squaredNorm();
  if (!(nn > 0.0)) return;
  const Vec3 ap = p - t[0];
  if ((t[1] - t[0]).cross(ap).dot(n) < 0.0 || (t[2] - t[1]).cross(p - t[1]).dot(n) < 0.0 ||
      (t[0] - t[2]).cross(p - t[2]).dot(n) < 0.0) {
    return;
  }
  const Vec3 q = p - (ap.dot(n) / nn) * n;
  if (p_on_a) {
    consider(best, best_sq, p, q);
  } else {
    consider(best, best_sq, q, p);
  }
}

}  // namespace

namespace {

// The closest pair over vertex-face and edge-edge features: the distance of disjoint triangles,
// and a common point (distance ~0) of touching ones.
ClosestPoints feature_closest_pair(const Triangle& a, const Triangle& b) {
  ClosestPoints best;
  double best_sq = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const ClosestPoints e = segment_segment_distance(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
      consider(best, best_sq, e.on_a, e.on_b);
    }
  }
  const Vec3 na = (a[1] - a[0]).cross(a[2] - a[0]), nb = (b[1] - b[0]).cross(b[2] - b[0]);
  for (int i = 0; i < 3; ++i) {
    vertex_face(best, best_sq, a[i], b, nb, true);
    vertex_face(best, best_sq, b[i], a, na, false);
  }
  best.distance = std::sqrt(best_sq);
  return best;
}

}  // namespace

Vec3 intersection_point(const Triangle& a, const Triangle& b) {
  // An edge of one triangle that crosses the other's plane inside it.
  for (int pass = 0; pass < 2; ++pass) {
    const Triangle& s = pass == 0 ? a : b;
    const Triangle& t = pass == 0 ? b : a;
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    for (int i = 0; i < 3; ++i) {
      const Vec3& u = s[i];
      const Vec3& v = s[(i + 1) % 3];
      const double du = (u - t[0]).dot(n), dv = (v - t[0]).dot(n);
      if (du * dv > 0.0 || du == dv) continue;
      const Vec3 x = u + (du / (du - dv)) * (v - u);
      if ((closest_point_on_triangle(x, t[0], t[1], t[2]) - x).squaredNorm() <=
          1e-24 * (1.0 + x.squaredNorm())) {
        return x;
      }
    }
  }
  // Coplanar or degenerate contact: a contained vertex or crossing edges.
  const ClosestPoints c = feature_closest_pair(a, b);
  return 0.5 * (c.on_a + c.on_b);
}

ClosestPoints triangle_triangle_distance(const Triangle& a_in, const Triangle& b_in) {
  // Work relative to a's first vertex: differences of nearby large coordinates are exact.
  const Vec3 origin = a_in[0];
  Triangle a, b;
  for (int i = 0; i < 3; ++i) {
    a[i] = a_in[i] - origin;
    b[i] = b_in[i] - origin;
  }
  ClosestPoints best;
  // The exact decision is made on the given coordinates (the shifted copies may have rounded);
  // a certified plane separation settles most pairs without it.
  const bool apart = detail::plane_separates(detail::plane_of(b_in[0], b_in[1], b_in[2]), a_in[0], a_in[1], a_in[2]) ||
                     detail::plane_separates(detail::plane_of(a_in[0], a_in[1], a_in[2]), b_in[0], b_in[1], b_in[2]);
  if (!apart && triangles_intersect(a_in, b_in)) {
    best.on_a = best.on_b = intersection_point(a, b) + origin;
    return best;
  }
  // Disjoint triangles: the closest pair is vertex-face or edge-edge.
  best = feature_closest_pair(a, b);
  best.on_a += origin;
  best.on_b += origin;
  return best;
}

}  // namespace bvh_collision
