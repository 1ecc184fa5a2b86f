// The geometry layer against CGAL's exact kernels: orientation predicates, triangle-triangle
// intersection (random, grid-degenerate and named hard cases) and distances with witnesses.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/geometry/predicates.h"
#include "cgal_oracle.h"
#include "hard_cases.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

using test::cgal_orient3d;
using test::hard_cases;
using test::NamedCase;
using test::cgal_segment_distance;
using test::cgal_triangle_distance;
using test::cgal_triangles_intersect;

std::mt19937_64& rng() {
  static std::mt19937_64 r(20261122);
  return r;
}

Vec3 random_point(double lo = 0.0, double hi = 1.0) {
  std::uniform_real_distribution<double> u(lo, hi);
  return {u(rng()), u(rng()), u(rng())};
}

// Points on a small integer grid: coplanar, collinear, shared and zero-area cases abound.
// Scaling by a power of two and adding a power-of-two offset keep every coordinate exact.
Vec3 grid_point(int n, double scale, double offset) {
  std::uniform_int_distribution<int> u(0, n);
  return Vec3(u(rng()), u(rng()), u(rng())) * scale + Vec3::Constant(offset);
}

Triangle tri(const Vec3& a, const Vec3& b, const Vec3& c) { return Triangle{{a, b, c}}; }

// ---------------------------------------------------------------------------------- predicates

TEST(Predicates, Orient3dMatchesCgalOnRandomPoints) {
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a = random_point(), b = random_point(), c = random_point(), d = random_point();
    ASSERT_EQ(orient3d(a, b, c, d), cgal_orient3d(a, b, c, d));
  }
}

TEST(Predicates, Orient3dMatchesCgalOnNearlyCoplanarPoints) {
  // d is computed on the plane of a, b, c and then nudged by a few ulps: the floating-point
  // determinant is noise here, so the filter fails and the exact path decides.
  int exact_zero = 0, nonzero = 0;
  for (int i = 0; i < 20000; ++i) {
    const double scale = std::pow(10.0, std::uniform_int_distribution<int>(-3, 4)(rng()));
    const Vec3 offset = random_point(-1e4, 1e4);
    const Vec3 a = offset + scale * random_point(), b = offset + scale * random_point();
    const Vec3 c = offset + scale * random_point();
    const double u = std::uniform_real_distribution<double>(-1, 2)(rng());
    const double v = std::uniform_real_distribution<double>(-1, 2)(rng());
    Vec3 d = a + u * (b - a) + v * (c - a);
    const int nudge = std::uniform_int_distribution<int>(-2, 2)(rng());
    for (int k = 0; k < std::abs(nudge); ++k) {
      d.z() = std::nextafter(d.z(), nudge > 0 ? INFINITY : -INFINITY);
    }
    const int ours = orient3d(a, b, c, d);
    ASSERT_EQ(ours, cgal_orient3d(a, b, c, d)) << "case " << i;
    (ours == 0 ? exact_zero : nonzero)++;
  }
  EXPECT_GT(nonzero, 0);
}

TEST(Predicates, Orient3dExactZeroOnGrid) {
  for (int i = 0; i < 20000; ++i) {
    const Vec3 a = grid_point(3, 0.25, 8192), b = grid_point(3, 0.25, 8192);
    const Vec3 c = grid_point(3, 0.25, 8192), d = grid_point(3, 0.25, 8192);
    ASSERT_EQ(orient3d(a, b, c, d), cgal_orient3d(a, b, c, d));
  }
}

TEST(Predicates, Orient2dMatchesCgal) {
  for (int i = 0; i < 20000; ++i) {
    const bool grid = i % 2 == 0;
    const Vec3 a = grid ? grid_point(4, 1.0 / 8, 1024) : random_point();
    const Vec3 b = grid ? grid_point(4, 1.0 / 8, 1024) : random_point();
    Vec3 c = grid ? grid_point(4, 1.0 / 8, 1024) : a + 0.37 * (b - a);
    for (int k = 0; k < 3; ++k) {
      ASSERT_EQ(orient2d(a, b, c, k), test::cgal_orient2d(a, b, c, k)) << "case " << i << " axis " << k;
    }
  }
}

TEST(Predicates, ProjectionAxisIsMinusOneExactlyForZeroArea) {
  EXPECT_EQ(projection_axis(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, 2)), -1);
  EXPECT_EQ(projection_axis(Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)), -1);
  EXPECT_EQ(projection_axis(Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)), 2);
  // A sliver one ulp off the line is not degenerate.
  EXPECT_GE(projection_axis(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(2, 2, std::nextafter(2.0, 3.0))), 0);
}

// ------------------------------------------------------------------- triangle intersection

TEST(TriangleIntersection, MatchesCgalOnRandomTriangles) {
  int hits = 0;
  for (int i = 0; i < 50000; ++i) {
    const Triangle a = tri(random_point(), random_point(), random_point());
    const Triangle b = tri(random_point(), random_point(), random_point());
    const bool expected = cgal_triangles_intersect(a, b);
    ASSERT_EQ(triangles_intersect(a, b), expected) << "case " << i;
    ASSERT_EQ(triangles_intersect(b, a), expected) << "case " << i << " swapped";
    hits += expected;
  }
  EXPECT_GT(hits, 5000);  // both answers well represented
  EXPECT_LT(hits, 45000);
}

TEST(TriangleIntersection, MatchesCgalOnDegenerateGridTriangles) {
  // Coordinates on a 4x4x4 grid: coplanar, shared-edge, shared-vertex, touching and zero-area
  // triangles are common. Repeated at several scales and far from the origin.
  const double scales[] = {1.0 / 1024, 1.0, 128.0};
  const double offsets[] = {0.0, 1024.0, 8192.0};
  int hits = 0, degenerate = 0;
  for (double scale : scales) {
    for (double offset : offsets) {
      for (int i = 0; i < 15000; ++i) {
        const Triangle a = tri(grid_point(3, scale, offset), grid_point(3, scale, offset), grid_point(3, scale, offset));
        const Triangle b = tri(grid_point(3, scale, offset), grid_point(3, scale, offset), grid_point(3, scale, offset));
        const bool expected = cgal_triangles_intersect(a, b);
        ASSERT_EQ(triangles_intersect(a, b), expected)
            << "scale " << scale << " offset " << offset << " case " << i << "\n a " << a[0].transpose()
            << " | " << a[1].transpose() << " | " << a[2].transpose() << "\n b " << b[0].transpose()
            << " | " << b[1].transpose() << " | " << b[2].transpose();
        hits += expected;
        degenerate += projection_axis(a[0], a[1], a[2]) < 0;
      }
    }
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(degenerate, 1000);
}

TEST(TriangleIntersection, MatchesCgalOnNearContactPairs) {
  // b is a copy of a moved by a tiny vector: contact decided at the last bits.
  for (int i = 0; i < 20000; ++i) {
    const Triangle a = tri(random_point(), random_point(), random_point());
    const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]).normalized();
    const double step = std::ldexp(1.0, -std::uniform_int_distribution<int>(30, 60)(rng()));
    const double sign = (i % 2 == 0) ? 1.0 : -1.0;
    Triangle b = tri(a[0] + sign * step * n, random_point(), random_point());
    if (i % 3 == 0) b = tri(a[0] + sign * step * n, a[1] + random_point(-1, 1), a[2] + sign * step * n);
    ASSERT_EQ(triangles_intersect(a, b), cgal_triangles_intersect(a, b)) << "case " << i;
  }
}

TEST(TriangleIntersection, NamedHardCases) {
  for (const NamedCase& c : hard_cases()) {
    SCOPED_TRACE(c.name);
    EXPECT_EQ(cgal_triangles_intersect(c.a, c.b), c.intersect) << "the case's expectation is wrong";
    EXPECT_EQ(triangles_intersect(c.a, c.b), c.intersect);
    EXPECT_EQ(triangles_intersect(c.b, c.a), c.intersect);
    // Far from the origin (exact power-of-two offset) the answer is the same.
    for (double offset : {1024.0, 8192.0}) {
      Triangle a = c.a, b = c.b;
      for (int i = 0; i < 3; ++i) {
        a[i] += Vec3::Constant(offset);
        b[i] += Vec3::Constant(offset);
      }
      EXPECT_EQ(triangles_intersect(a, b), cgal_triangles_intersect(a, b)) << "offset " << offset;
    }
  }
}

// ---------------------------------------------------------------------------------- distances

// |ours - exact| within 1e-9 relative, or a few ulps of the coordinates' magnitude for
// distances below what doubles at that magnitude can resolve.
void expect_distance_close(double ours, double exact, double coordinate_scale, const std::string& what) {
  const double allowed = 1e-9 * exact + 8 * std::numeric_limits<double>::epsilon() * coordinate_scale;
  EXPECT_NEAR(ours, exact, allowed) << what;
}

void expect_witnesses_consistent(const ClosestPoints& d, const Triangle& a, const Triangle& b, double scale) {
  const double slack = 64 * std::numeric_limits<double>::epsilon() * scale;
  EXPECT_NEAR((d.on_a - d.on_b).norm(), d.distance, slack + 1e-12 * d.distance);
  EXPECT_LE((closest_point_on_triangle(d.on_a, a[0], a[1], a[2]) - d.on_a).norm(), slack);
  EXPECT_LE((closest_point_on_triangle(d.on_b, b[0], b[1], b[2]) - d.on_b).norm(), slack);
}

// triangle_plane_beyond lets a query skip a triangle without its closest point: wherever it says
// so, the exact distance (CGAL's, the point as a zero-area triangle) and the computed one are at
// least the limit. Limits are drawn within a millionth of the exact distance, points near the
// plane, on it, far from the origin, and triangles degenerate on a grid; the skip must also be
// taken where the plane is twice the limit away.
TEST(Distance, TrianglePlaneBeyondSkipsOnlyTrianglesAtLeastTheLimitAway) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  int skipped = 0, must_skip = 0, cases = 0;
  for (int i = 0; i < 6000; ++i, ++cases) {
    const bool grid = i % 3 == 2;
    const Vec3 offset = i % 4 == 1 ? random_point(-1e3, 1e3) : Vec3::Zero();
    const Triangle t = grid ? tri(grid_point(3, 0.5, 8), grid_point(3, 0.5, 8), grid_point(3, 0.5, 8))
                            : tri(offset + random_point(), offset + random_point(), offset + random_point());
    const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
    // A point off the plane by a chosen height (some on it, some within a few ulps of it).
    const double height = i % 5 == 0 ? 0.0 : std::pow(10.0, -1.0 - 14.0 * std::abs(unit(rng())));
    const Vec3 on_plane = t[0] + random_point(-1, 1);
    const Vec3 along = n.norm() > 0.0 ? Vec3(n.normalized()) : Vec3::UnitZ();
    const Vec3 p = on_plane - along * (along.dot(on_plane - t[0])) + along * height * (unit(rng()) < 0 ? -1.0 : 1.0);
    const double exact = cgal_triangle_distance(t, tri(p, p, p));
    const double computed = (closest_point_on_triangle(p, t[0], t[1], t[2]) - p).norm();
    for (const double factor : {0.0, 0.5, 1.0 - 1e-6, 1.0, 1.0 + 1e-6, 2.0}) {
      const double limit = exact * factor;
      if (!triangle_plane_beyond(p, t[0], t[1], t[2], limit)) continue;
      ++skipped;
      ASSERT_GT(exact, limit) << "case " << i << " factor " << factor;
      ASSERT_GE(computed, limit) << "case " << i << " factor " << factor;
    }
    // Taken where it should be: a plane farther than twice the limit, well above the slack.
    if (n.norm() > 1e-6 && height > 1e-6) {
      ++must_skip;
      ASSERT_TRUE(triangle_plane_beyond(p, t[0], t[1], t[2], 0.5 * height)) << "case " << i;
    }
  }
  EXPECT_GT(must_skip, cases / 5);  // (heights above 1e-6: about 5 in 14 of those off the plane)
  EXPECT_GT(skipped, cases / 4);
  for (const double limit : {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()}) {
    EXPECT_FALSE(triangle_plane_beyond(Vec3(0, 0, 5), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), limit));
  }
  EXPECT_FALSE(triangle_plane_beyond(Vec3(0, 0, 5), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(2, 0, 0), 1.0));  // no plane
  EXPECT_TRUE(triangle_plane_beyond(Vec3(0, 0, 5), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 4.9));
  EXPECT_FALSE(triangle_plane_beyond(Vec3(0, 0, 5), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), 5.0));
}

TEST(Distance, TriangleTriangleMatchesCgalOnRandomPairs) {
  for (int i = 0; i < 5000; ++i) {
    const Triangle a = tri(random_point(), random_point(), random_point());
    const Vec3 shift = random_point(-1, 1);
    const Triangle b = tri(random_point() + shift, random_point() + shift, random_point() + shift);
    const ClosestPoints d = triangle_triangle_distance(a, b);
    expect_distance_close(d.distance, cgal_triangle_distance(a, b), 2.0, "case " + std::to_string(i));
    expect_witnesses_consistent(d, a, b, 2.0);
    if (HasFailure()) return;
  }
}

TEST(Distance, TriangleTriangleMatchesCgalOnGridPairsIncludingDegenerate) {
  for (int i = 0; i < 5000; ++i) {
    const Triangle a = tri(grid_point(3, 0.5, 1024), grid_point(3, 0.5, 1024), grid_point(3, 0.5, 1024));
    const Triangle b = tri(grid_point(3, 0.5, 1024), grid_point(3, 0.5, 1024), grid_point(3, 0.5, 1024));
    const ClosestPoints d = triangle_triangle_distance(a, b);
    expect_distance_close(d.distance, cgal_triangle_distance(a, b), 1024.0, "case " + std::to_string(i));
    expect_witnesses_consistent(d, a, b, 1024.0);
    if (HasFailure()) return;
  }
}

TEST(Distance, TriangleTriangleNearContact) {
  // Gaps from 1e-3 down to 1e-15 along a's normal, including rotated copies.
  for (int i = 0; i < test::sized(3000); ++i) {
    const Triangle a = tri(random_point(), random_point(), random_point());
    const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]).normalized();
    const double gap = std::pow(10.0, -std::uniform_int_distribution<int>(3, 15)(rng()));
    const Triangle b = tri(a[0] + gap * n, a[0] + gap * n + random_point(-1, 1), a[1] + (gap + 0.5) * n);
    const ClosestPoints d = triangle_triangle_distance(a, b);
    expect_distance_close(d.distance, cgal_triangle_distance(a, b), 2.0, "case " + std::to_string(i));
    if (HasFailure()) return;
  }
}

TEST(Distance, ParallelEdgesAt1e12) {
  // Edges parallel (and nearly parallel) at 1e-12: the a*e - b*b formula fails here.
  for (int i = 0; i < 2000; ++i) {
    const Vec3 p1 = random_point(), dir = random_point(-1, 1).normalized();
    const Vec3 perp = dir.cross(random_point(-1, 1)).normalized();
    const double length = 0.1 + random_point().x();
    const double twist = (i % 2 == 0) ? 0.0 : 1e-9 * random_point().y();
    const Vec3 p2 = p1 + length * dir;
    const Vec3 q1 = p1 + 1e-12 * perp + 0.3 * length * dir;
    const Vec3 q2 = q1 + length * (dir + twist * perp);
    const ClosestPoints d = segment_segment_distance(p1, p2, q1, q2);
    expect_distance_close(d.distance, cgal_segment_distance(p1, p2, q1, q2), 2.0, "case " + std::to_string(i));
    if (HasFailure()) return;
  }
}

TEST(Distance, SegmentSegmentMatchesCgal) {
  for (int i = 0; i < 20000; ++i) {
    const bool degenerate = i % 10 == 0;
    const Vec3 p1 = random_point(), p2 = degenerate ? p1 : random_point();
    const Vec3 q1 = random_point(), q2 = random_point();
    const ClosestPoints d = segment_segment_distance(p1, p2, q1, q2);
    expect_distance_close(d.distance, cgal_segment_distance(p1, p2, q1, q2), 1.0, "case " + std::to_string(i));
    if (HasFailure()) return;
  }
}

TEST(Distance, HardCasesAgreeWithCgal) {
  for (const NamedCase& c : hard_cases()) {
    SCOPED_TRACE(c.name);
    const ClosestPoints d = triangle_triangle_distance(c.a, c.b);
    const double exact = cgal_triangle_distance(c.a, c.b);
    expect_distance_close(d.distance, exact, 2.0, c.name);
    EXPECT_EQ(d.distance == 0.0, c.intersect);
  }
}

TEST(Distance, TranslationFarFromOriginChangesNothing) {
  for (int i = 0; i < 2000; ++i) {
    const Triangle a = tri(grid_point(8, 1.0 / 64, 0), grid_point(8, 1.0 / 64, 0), grid_point(8, 1.0 / 64, 0));
    const Triangle b = tri(grid_point(8, 1.0 / 64, 0), grid_point(8, 1.0 / 64, 0), grid_point(8, 1.0 / 64, 0));
    const double base = triangle_triangle_distance(a, b).distance;
    for (double offset : {1024.0, 8192.0}) {
      Triangle ta = a, tb = b;
      for (int k = 0; k < 3; ++k) {
        ta[k] += Vec3::Constant(offset);
        tb[k] += Vec3::Constant(offset);
      }
      ASSERT_EQ(triangles_intersect(ta, tb), triangles_intersect(a, b));
      ASSERT_NEAR(triangle_triangle_distance(ta, tb).distance, base, 1e-12 * (1 + base)) << "case " << i;
    }
  }
}

// Why a mesh is not closed: a removed face leaves its three edges without a reverse; a flipped
// face makes its edges repeat in one direction; a closed box has none.
TEST(Mesh, OpenEdgesSayWhyAMeshIsNotClosed) {
  const TriangleMesh box = box_mesh(Vec3(1, 2, 3));
  EXPECT_TRUE(open_edges(box).empty());
  EXPECT_TRUE(is_closed(box));
  TriangleMesh hole = box;
  hole.triangles.pop_back();
  const auto holes = open_edges(hole);
  ASSERT_EQ(holes.size(), 3u);
  for (const MeshEdge& e : holes) {
    EXPECT_EQ(e.fault, MeshEdge::Fault::kBoundary);
  }
  EXPECT_FALSE(is_closed(hole));
  TriangleMesh flipped = box;
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  bool repeated = false;
  for (const MeshEdge& e : open_edges(flipped)) repeated = repeated || e.fault == MeshEdge::Fault::kRepeated;
  EXPECT_TRUE(repeated);
  EXPECT_FALSE(is_closed(flipped));
}

}  // namespace
// Ray entry into a ball against bisection on the squared distance in long double: the first s
// in [0, length] where |o + s u - c| <= r, found without the quadratic formula.
TEST(RayBall, EntryMatchesBisection) {
  std::mt19937_64 r(99);
  std::uniform_real_distribution<double> u(-1.0, 1.0), size(0.01, 1.0);
  int hits = 0, misses = 0, inside = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 origin(u(r), u(r), u(r)), centre(u(r), u(r), u(r));
    const double radius = 0.5 * size(r), length = 2.0 * size(r);
    // Half the rays aim near the ball (hits and grazes), half anywhere (mostly misses).
    const Vec3 jitter(u(r), u(r), u(r));
    const Vec3 aim = i % 2 ? Vec3(centre + 1.2 * radius * jitter) : Vec3(origin + jitter);
    if ((aim - origin).norm() < 1e-6) continue;
    const Vec3 unit = (aim - origin).normalized();
    auto f = [&](long double s) {
      long double q = 0;
      for (int k = 0; k < 3; ++k) {
        const long double d = origin[k] + s * unit[k] - centre[k];
        q += d * d;
      }
      return q - static_cast<long double>(radius) * radius;
    };
    const double got = ray_ball_entry(origin, unit, length, centre, radius);
    if (f(0) <= 0) {
      EXPECT_EQ(got, 0.0);
      ++inside;
      continue;
    }
    const long double nearest = std::clamp<long double>((centre - origin).dot(unit), 0.0L, length);
    if (f(nearest) > 1e-12L) {
      EXPECT_TRUE(std::isinf(got)) << i;
      ++misses;
      continue;
    }
    if (f(nearest) > -1e-12L) continue;  // grazing within rounding: either answer
    long double lo = 0, hi = nearest;
    for (int k = 0; k < 200; ++k) (f(0.5L * (lo + hi)) > 0 ? lo : hi) = 0.5L * (lo + hi);
    EXPECT_NEAR(got, static_cast<double>(hi), 1e-9) << i;
    ++hits;
  }
  EXPECT_GT(hits, 1000);
  EXPECT_GT(misses, 1000);
  EXPECT_GT(inside, 100);
}

}  // namespace bvh_collision
