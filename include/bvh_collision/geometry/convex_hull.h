// Convex hulls of point sets, and certified distances between convex hulls.
//
// The hull is built incrementally with the exact orient3d predicate, so it is the exact hull of
// the given doubles: every input point lies in it, and its vertices are input points. That makes
// the hull's support function (the furthest vertex along a direction) exactly the support function
// of the input, which is what the certified distance bound below relies on.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

struct ConvexHull {
  std::vector<Vec3> vertices;                // input points that are hull vertices
  std::vector<std::array<int, 3>> faces;     // outward (counter-clockwise seen from outside);
                                             // empty when the points are coplanar or fewer than 4
  double extent = 0.0;                       // the largest vertex norm (for rounding margins)
  std::uint64_t orientation_tests = 0;       // the build's work: point-against-face tests
  // The faces' edges per vertex: neighbours[neighbour_start[v], neighbour_start[v + 1]) (empty
  // without faces), and the vertices furthest along -x, +x, -y, +y, -z, +z (hull_support's starts).
  std::vector<std::uint32_t> neighbour_start, neighbours;
  std::array<int, 6> extremes{};
  bool empty() const { return vertices.empty(); }
};

// The index of a vertex furthest along d (the hull's support function, exactly the input's, up to
// the dot products' rounding). A large hull is climbed along its edges from the best of its axis
// extremes, or from `from` when that is a vertex index (the last answer, when d has turned a little
// since, as GJK's directions do; a vertex as far whatever the start): on a convex polytope a vertex
// that no edge rises from is furthest. Where a neighbour is level with the climb within the
// rounding (a face almost square to d, where a climb could stall inside a flat face), the search
// spreads over the level vertices, not the whole hull. `work`, when given, counts the dot products.
int hull_support(const ConvexHull& hull, const Vec3& d, int from = -1, std::size_t* work = nullptr);

// The hull of `points`. When the points span no volume (all coplanar), `vertices` holds every
// distinct point (still a superset of the hull's vertices) and `faces` is empty.
ConvexHull convex_hull(const std::vector<Vec3>& points);

// Closest points between two convex hulls, a in its own frame and b placed by `b_in_a`.
struct ConvexDistance {
  bool intersecting = false;  // the hulls may touch or overlap (lower_bound is then 0)
  double lower_bound = 0.0;   // certified: the hulls' distance is at least this
  double distance = 0.0;      // the distance found (>= lower_bound, equal up to rounding)
  Vec3 on_a = Vec3::Zero();   // witness on a's hull, in a's frame
  Vec3 on_b = Vec3::Zero();   // witness on b's hull, in a's frame
  int vertex_a = -1;          // when on_a is a vertex of a's hull: its index, else -1
  int vertex_b = -1;          // when on_b is a vertex of b's hull: its index, else -1
  int support_queries = 0;    // support points asked of either set (the work done)
};

// GJK on the two vertex sets. The lower bound does not trust GJK's arithmetic: it is the gap
// between the two hulls along GJK's last search direction (or a final triangle's normal, when
// larger), from exact support values with a rounding margin, so it is a valid bound even when GJK
// stops early. A pair of hulls asked again by the same thread (a self pair at an interval's
// midpoint, then at its halves') starts from the simplex and support vertices it ended with: at a
// nearby pose GJK then takes a step or two, not the seven or eight of a cold start (ur5e's pairs).
// The answer is computed from the closest features alone: the same bits from any start that ends
// on the same features (generic poses; where faces lie parallel, equally close features may be
// found instead, whose answers agree to rounding).
ConvexDistance convex_distance(const ConvexHull& a, const ConvexHull& b, const Transform& b_in_a);

}  // namespace bvh_collision
