// Convex hulls and the certified GJK distance, against CGAL: extreme points (convex_hull_3) and
// the exact distance between two polytopes (Polytope_distance_d with an exact number type).
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <random>
#include <set>

#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/predicates.h"
#include "cgal_oracle.h"
#include "mesh_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(7);
  return r;
}

std::vector<Vec3> random_cloud(int n, double size) {
  std::uniform_real_distribution<double> u(-size, size);
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) p.emplace_back(u(rng()), u(rng()), u(rng()));
  return p;
}

// Points on a small integer grid: many coplanar and collinear hull points.
std::vector<Vec3> grid_cloud(int n, int cells, double scale) {
  std::uniform_int_distribution<int> u(0, cells);
  std::vector<Vec3> p;
  for (int i = 0; i < n; ++i) p.push_back(Vec3(u(rng()), u(rng()), u(rng())) * scale);
  return p;
}

Transform random_pose(double reach) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::Quaterniond q(Eigen::Vector4d(u(rng()), u(rng()), u(rng()), u(rng())).normalized());
  return {q.toRotationMatrix(), Vec3(u(rng()), u(rng()), u(rng())) * reach};
}

// Closed and consistently oriented: every directed edge's reverse appears exactly once.
void expect_closed_surface(const ConvexHull& hull) {
  std::map<std::pair<int, int>, int> edges;
  for (const auto& f : hull.faces) {
    for (int k = 0; k < 3; ++k) ++edges[{f[k], f[(k + 1) % 3]}];
  }
  for (const auto& [e, count] : edges) {
    ASSERT_EQ(count, 1);
    ASSERT_EQ(edges.count({e.second, e.first}), 1u);
  }
}

// The support function along random directions equals the input's, to the last bit.
void expect_input_support(const std::vector<Vec3>& points, const ConvexHull& hull, int directions) {
  for (int i = 0; i < directions; ++i) {
    const Vec3 d = random_cloud(1, 1.0)[0];
    double best_in = -1e300, best_hull = -1e300;
    for (const Vec3& p : points) best_in = std::max(best_in, d.dot(p));
    for (const Vec3& p : hull.vertices) best_hull = std::max(best_hull, d.dot(p));
    EXPECT_EQ(best_in, best_hull);
  }
}

// The properties the distance bound relies on, each checked exactly or by brute force.
void expect_valid_hull(const std::vector<Vec3>& points, const ConvexHull& hull, const std::string& what) {
  SCOPED_TRACE(what);
  ASSERT_FALSE(hull.faces.empty());
  const std::set<std::array<double, 3>> input = [&] {
    std::set<std::array<double, 3>> s;
    for (const Vec3& p : points) s.insert({p.x(), p.y(), p.z()});
    return s;
  }();
  for (const Vec3& v : hull.vertices) {
    EXPECT_TRUE(input.count({v.x(), v.y(), v.z()})) << "vertex not an input point";
  }
  expect_closed_surface(hull);
  // Every input point on the inner side of (or on) every face, exactly.
  int outside = 0;
  for (const auto& f : hull.faces) {
    for (const Vec3& p : points) outside += orient3d(hull.vertices[f[0]], hull.vertices[f[1]], hull.vertices[f[2]], p) < 0;
  }
  EXPECT_EQ(outside, 0);
  // Every extreme point CGAL finds is one of ours.
  std::set<std::array<double, 3>> ours;
  for (const Vec3& v : hull.vertices) ours.insert({v.x(), v.y(), v.z()});
  for (const Vec3& e : test::cgal_extreme_points(points)) {
    EXPECT_TRUE(ours.count({e.x(), e.y(), e.z()})) << "missing extreme point";
  }
  expect_input_support(points, hull, 200);
}

TEST(ConvexHull, RandomClouds) {
  for (const int n : {4, 5, 10, 100, 2000}) {
    const auto p = random_cloud(n, 1.0);
    expect_valid_hull(p, convex_hull(p), "random " + std::to_string(n));
  }
}

TEST(ConvexHull, GridCloudsWithCoplanarAndCollinearPoints) {
  for (const int cells : {1, 2, 3, 8}) {
    for (const double scale : {1.0, 1.0 / 1024, 1024.0}) {
      const auto p = grid_cloud(400, cells, scale);
      expect_valid_hull(p, convex_hull(p), "grid " + std::to_string(cells));
    }
  }
}

TEST(ConvexHull, SpherePointsAndFarOffsets) {
  std::vector<Vec3> p;
  for (const Vec3& x : random_cloud(500, 1.0)) p.push_back(x.normalized() + Vec3(1e4, -1e4, 3e3));
  expect_valid_hull(p, convex_hull(p), "sphere at 1e4");
}

// Every point a vertex (on a sphere): the incremental build that inserted each point against
// every face took minutes for 200,000 such points (O(n^2)); the randomized one takes about half
// a second. Checked without the O(n faces) containment loop: a closed, consistently oriented
// surface over exactly the input points, whose support function equals the input's.
TEST(ConvexHull, TwoHundredThousandPointsOnASphere) {
  std::mt19937_64 gen(5);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Vec3> p;
  for (int i = 0; i < test::sized(200000); ++i) p.push_back(Vec3(g(gen), g(gen), g(gen)).normalized());
  const ConvexHull hull = convex_hull(p);
  std::set<std::array<double, 3>> distinct;
  for (const Vec3& x : p) distinct.insert({x.x(), x.y(), x.z()});
  EXPECT_EQ(hull.vertices.size(), distinct.size());
  EXPECT_EQ(hull.faces.size(), 2 * hull.vertices.size() - 4);  // a closed triangulated sphere
  expect_closed_surface(hull);
  expect_input_support(p, hull, 50);
}

TEST(ConvexHull, RobotMeshes) {
  BVH_REQUIRE_ROBOTS();
  for (const char* file : {"panda/moveit_resources_panda_description/meshes/collision/link1.stl", "panda/moveit_resources_panda_description/meshes/collision/hand.stl",
                           "ur5e/ur_description/meshes/ur5e/collision/shoulder.stl", "ur5e/ur_description/meshes/ur5e/collision/forearm.stl"}) {
    const TriangleMesh m = test::robot_mesh(file);
    const ConvexHull h = convex_hull(m.vertices);
    expect_valid_hull(m.vertices, h, file);
    EXPECT_LT(h.vertices.size(), m.vertices.size());
  }
}

// hull_support climbs a large hull's edges: the vertex it names is as far along d as the furthest
// of all (brute force), for random directions, the axes, and the faces' normals, their reverses
// and slight tilts of them (where many vertices of a flat face tie, and a climb could stall on a
// vertex inside the face), on random, grid (coplanar and collinear points) and robot hulls.
TEST(ConvexHull, SupportClimbsToTheFurthestVertex) {
  BVH_REQUIRE_ROBOTS();
  std::vector<std::pair<std::string, std::vector<Vec3>>> clouds = {
      {"random", random_cloud(2000, 1.0)}, {"grid", grid_cloud(3000, 8, 0.01)}, {"grid coarse", grid_cloud(400, 2, 1.0)}};
  for (const char* file : {"panda/moveit_resources_panda_description/meshes/collision/link1.stl", "panda/moveit_resources_panda_description/meshes/collision/hand.stl"}) {
    clouds.emplace_back(file, test::robot_mesh(file).vertices);
  }
  std::normal_distribution<double> g(0.0, 1.0);
  int climbed = 0;
  for (const auto& [name, points] : clouds) {
    const ConvexHull hull = convex_hull(points);
    std::vector<Vec3> directions = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
    for (int i = 0; i < 300; ++i) directions.emplace_back(g(rng()), g(rng()), g(rng()));
    for (const auto& f : hull.faces) {
      const Vec3 n = (hull.vertices[f[1]] - hull.vertices[f[0]]).cross(hull.vertices[f[2]] - hull.vertices[f[0]]);
      for (const Vec3& d : {n, Vec3(-n), Vec3(n + 1e-9 * n.norm() * Vec3(g(rng()), g(rng()), g(rng())))}) directions.push_back(d);
    }
    for (const Vec3& d : directions) {
      double furthest = -std::numeric_limits<double>::infinity();
      for (const Vec3& v : hull.vertices) furthest = std::max(furthest, d.dot(v));
      const int k = hull_support(hull, d);
      ASSERT_GE(d.dot(hull.vertices[k]), furthest - 1e-12 * d.norm() * hull.extent) << name;
    }
    climbed += hull.vertices.size() >= 32;
  }
  EXPECT_GE(climbed, 3);  // hulls large enough to be climbed
}

// A climb that stalls on a level face searches the level vertices around it, not the hull: the
// work (dot products) of a query square to a face, or started from any vertex (GJK starts each
// climb from its last answer), is bounded by a fraction of the hull, and the vertex named is as far
// along d as the furthest (brute force). Robot meshes whose large flat and cylindrical faces tie
// many vertices (before, every tie searched the whole hull: a third of a planning run's time).
TEST(ConvexHull, ALevelClimbSearchesTheLevelVerticesNotTheHull) {
  BVH_REQUIRE_ROBOTS();
  std::normal_distribution<double> g(0.0, 1.0);
  for (const char* file : {"ur5e/ur_description/meshes/ur5e/collision/shoulder.stl", "ur5e/ur_description/meshes/ur5e/collision/forearm.stl",
                           "ur5e/ur_description/meshes/ur5e/collision/upperarm.stl", "panda/moveit_resources_panda_description/meshes/collision/link1.stl"}) {
    const ConvexHull hull = convex_hull(test::robot_mesh(file).vertices);
    ASSERT_GE(hull.vertices.size(), 128u) << file;
    std::vector<Vec3> directions = {Vec3::UnitX(), -Vec3::UnitX(), Vec3::UnitY(), -Vec3::UnitY(), Vec3::UnitZ(), -Vec3::UnitZ()};
    for (const auto& f : hull.faces) {
      directions.push_back((hull.vertices[f[1]] - hull.vertices[f[0]]).cross(hull.vertices[f[2]] - hull.vertices[f[0]]));
    }
    for (int i = 0; i < 200; ++i) directions.emplace_back(g(rng()), g(rng()), g(rng()));
    std::size_t work = 0, worst = 0;
    for (std::size_t i = 0; i < directions.size(); ++i) {
      const Vec3& d = directions[i];
      double furthest = -std::numeric_limits<double>::infinity();
      for (const Vec3& v : hull.vertices) furthest = std::max(furthest, d.dot(v));
      const int from = i % 2 == 0 ? -1 : static_cast<int>(i % hull.vertices.size());
      std::size_t one = 0;
      const int k = hull_support(hull, d, from, &one);
      ASSERT_GE(d.dot(hull.vertices[k]), furthest - 1e-12 * d.norm() * hull.extent) << file;
      work += one;
      worst = std::max(worst, one);
    }
    std::printf("%s: %zu vertices, %zu queries, %.1f dot products a query (most %zu)\n", file, hull.vertices.size(), directions.size(),
                static_cast<double>(work) / directions.size(), worst);
    EXPECT_LT(work, directions.size() * hull.vertices.size() / 3) << file;  // a query square to a face searched all, before
    EXPECT_LT(worst, hull.vertices.size()) << file;
  }
}

// A climb that starts inside a flat face square to d finds every neighbour level with it: it must
// not answer that vertex (the face is the lowest, not the highest, along d) but search them all.
// (Built by hand: a fan of 8 around the centre of the base, a ring of 24 above it and a top; every
// climb starts at the base's centre.)
TEST(ConvexHull, AClimbLevelOnAFlatFaceSearchesEveryVertex) {
  ConvexHull h;
  std::vector<std::vector<std::uint32_t>> around;
  auto add = [&](const Vec3& v) {
    h.vertices.push_back(v);
    around.emplace_back();
    return static_cast<std::uint32_t>(h.vertices.size() - 1);
  };
  auto link = [&](std::uint32_t a, std::uint32_t b) { around[a].push_back(b), around[b].push_back(a); };
  const std::uint32_t centre = add(Vec3::Zero());
  std::vector<std::uint32_t> base, ring;
  for (int i = 0; i < 8; ++i) base.push_back(add(Vec3(std::cos(i * M_PI / 4), std::sin(i * M_PI / 4), 0.0)));
  for (int i = 0; i < 24; ++i) ring.push_back(add(Vec3(0.8 * std::cos(i * M_PI / 12), 0.8 * std::sin(i * M_PI / 12), 0.5)));
  const std::uint32_t top = add(Vec3(0.0, 0.0, 1.0));
  for (int i = 0; i < 8; ++i) link(centre, base[i]), link(base[i], base[(i + 1) % 8]), link(base[i], ring[3 * i]);
  for (int i = 0; i < 24; ++i) link(ring[i], ring[(i + 1) % 24]), link(ring[i], top);
  h.neighbour_start.assign(1, 0);
  for (const auto& list : around) {
    h.neighbours.insert(h.neighbours.end(), list.begin(), list.end());
    h.neighbour_start.push_back(static_cast<std::uint32_t>(h.neighbours.size()));
  }
  h.extent = 1.0;
  h.extremes.fill(static_cast<int>(centre));
  ASSERT_GE(h.vertices.size(), 32u);  // large enough to be climbed
  EXPECT_EQ(hull_support(h, Vec3::UnitZ()), static_cast<int>(top));
  EXPECT_NE(hull_support(h, Vec3(0.3, 0.1, 1.0)), static_cast<int>(centre));
}

// A vertex no triangle uses is not on the surface: it must not become a hull vertex that the
// checker would take for a surface point.
TEST(ConvexHull, UsedVerticesLeaveOutUnreferencedPoints) {
  TriangleMesh m = box_mesh(Vec3(1, 1, 1));
  m.vertices.push_back(Vec3(5, 5, 5));
  const std::vector<Vec3> used = used_vertices(m);
  EXPECT_EQ(used.size(), 8u);
  const ConvexHull h = convex_hull(used);
  EXPECT_EQ(h.vertices.size(), 8u);
  for (const Vec3& v : h.vertices) {
    EXPECT_LE(v.cwiseAbs().maxCoeff(), 0.5);
  }
}

TEST(ConvexHull, DegenerateInputsKeepEveryDistinctPoint) {
  EXPECT_TRUE(convex_hull({}).empty());
  const ConvexHull two = convex_hull({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 0)});
  EXPECT_EQ(two.vertices.size(), 2u);
  EXPECT_TRUE(two.faces.empty());
  std::vector<Vec3> flat;
  for (int i = 0; i < 50; ++i) flat.push_back(Vec3(i % 7, i / 7, 0) * 0.1);
  const ConvexHull f = convex_hull(flat);
  EXPECT_TRUE(f.faces.empty());
  EXPECT_EQ(f.vertices.size(), 50u);
  const ConvexHull nan = convex_hull({Vec3(NAN, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1)});
  EXPECT_EQ(nan.vertices.size(), 4u);
  EXPECT_EQ(nan.faces.size(), 4u);
}

// --------------------------------------------------------------------------------- distance

double exact_distance(const std::vector<Vec3>& a, const std::vector<Vec3>& b) { return test::cgal_polytope_distance(a, b); }

struct DistanceCase {
  std::vector<Vec3> a, b;
  Transform b_in_a;
};

// `slack`: how far below the exact distance the bound may be and still count as tight.
void expect_certified(const DistanceCase& c, int& tight, int& total, double slack = 0.0) {
  const ConvexHull ha = convex_hull(c.a), hb = convex_hull(c.b);
  std::vector<Vec3> b_placed;
  for (const Vec3& p : hb.vertices) b_placed.push_back(c.b_in_a * p);
  const double truth = exact_distance(ha.vertices, b_placed);
  const ConvexDistance d = convex_distance(ha, hb, c.b_in_a);
  const double scale = 1e-12 * (ha.extent + hb.extent + c.b_in_a.t.norm());
  // Never above the truth (up to the rounding of the oracle's square root)...
  EXPECT_LE(d.lower_bound, truth * (1 + 1e-15)) << "bound above the exact distance";
  // ...the witnesses are points of the hulls at the distance reported...
  EXPECT_NEAR((d.on_a - d.on_b).norm(), d.distance, 1e-15 * (1 + d.distance));
  EXPECT_GE(d.distance, truth - scale);
  // ...and when the hulls are apart, the distance and the bound are the exact one.
  if (truth > scale) {
    ++total;
    EXPECT_FALSE(d.intersecting);
    EXPECT_NEAR(d.distance, truth, scale + 1e-9 * truth);
    tight += d.lower_bound >= truth - scale - slack;
    if (d.lower_bound < truth - scale - slack) {
      ADD_FAILURE() << "loose bound " << d.lower_bound << " for distance " << truth << " (GJK found " << d.distance
                    << ")";
    }
  }
}

TEST(ConvexDistance, RandomPolytopesAgainstCgalExact) {
  int tight = 0, total = 0;
  for (int i = 0; i < test::sized(1500); ++i) {
    const int n = 4 + static_cast<int>(rng()() % 60);
    DistanceCase c{random_cloud(n, 0.2), random_cloud(4 + static_cast<int>(rng()() % 60), 0.3), random_pose(0.9)};
    expect_certified(c, tight, total);
  }
  EXPECT_GT(total, test::sized(1500) / 3);
  EXPECT_EQ(tight, total) << "the certified bound should equal the distance when GJK converges";
}

TEST(ConvexDistance, FlatAndParallelFaces) {
  int tight = 0, total = 0;
  // Two boxes with parallel faces (the degenerate case of GJK), shifted along a face normal and
  // slid sideways; and two coplanar point sets. When edges line up exactly at a gap far below
  // the boxes' size, the witnesses' rounding tilts the direction of the bound: it stays within
  // 1e-9 of the size (a checker then falls back to the exact mesh query).
  const std::vector<Vec3> box = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
  for (const double gap : {0.0, 1e-12, 1e-6, 0.25, 3.0}) {
    for (const double slide : {0.0, 0.5, 0.999, 1.0, 1.5}) {
      expect_certified({box, box, Transform::Translation(Vec3(slide, 0.3 * slide, 1.0 + gap))}, tight, total, 1e-9);
    }
  }
  std::vector<Vec3> square = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0.5, 0.5, 0}};
  expect_certified({square, square, Transform::Translation(Vec3(0.2, 0.2, 0.5))}, tight, total);
  expect_certified({square, box, Transform::Translation(Vec3(2.0, 0.2, 0.0))}, tight, total);
  EXPECT_EQ(tight, total);
}

TEST(ConvexDistance, RobotMeshesAtRandomPoses) {
  BVH_REQUIRE_ROBOTS();
  const TriangleMesh a = test::robot_mesh("ur5e/ur_description/meshes/ur5e/collision/shoulder.stl");
  const TriangleMesh b = test::robot_mesh("panda/moveit_resources_panda_description/meshes/collision/hand.stl");
  int tight = 0, total = 0;
  for (int i = 0; i < 200; ++i) expect_certified({a.vertices, b.vertices, random_pose(0.3)}, tight, total);
  EXPECT_GT(total, 50);
  EXPECT_EQ(tight, total);
}

// A self pair's exact distance is asked at an interval's midpoint and then at its halves': the
// same two hulls at nearby poses. Each answer stays CGAL's exact distance, and a pair asked again
// starts from where it ended (its simplex and support vertices): a fraction of the support queries
// of the same distance asked cold (the hulls copied to addresses never asked before).
TEST(ConvexDistance, APairAskedAgainAtANearbyPoseStartsWhereItEnded) {
  BVH_REQUIRE_ROBOTS();
  const ConvexHull a = convex_hull(test::robot_mesh("ur5e/ur_description/meshes/ur5e/collision/forearm.stl").vertices);
  const ConvexHull b = convex_hull(test::robot_mesh("ur5e/ur_description/meshes/ur5e/collision/wrist3.stl").vertices);
  std::vector<std::unique_ptr<ConvexHull>> cold_copies;  // kept: each cold call's hulls at a fresh address
  long warm_queries = 0, cold_queries = 0;
  int asked = 0;
  const int sweeps = test::sanitized() ? 1 : 8;  // (CGAL's exact distance a pose: a second each under ASan)
  for (int motion = 0; motion < sweeps; ++motion) {
    // A sweep of b past a: turning about an axis through a point beside a, 200 poses 1 mrad apart.
    const Transform base = random_pose(0.05) * Transform::Translation(Vec3(0.0, 0.0, 0.35));
    const Vec3 axis = Vec3(random_pose(1.0).t).normalized();
    for (int step = 0; step < 200; ++step) {
      const Transform b_in_a = {Eigen::AngleAxisd(1e-3 * step, axis).toRotationMatrix() * base.R, base.t};
      std::vector<Vec3> placed;
      for (const Vec3& p : b.vertices) placed.push_back(b_in_a * p);
      const double truth = exact_distance(a.vertices, placed);
      if (!(truth > 1e-6)) continue;
      const ConvexDistance warm = convex_distance(a, b, b_in_a);
      cold_copies.push_back(std::make_unique<ConvexHull>(a));
      const ConvexDistance cold = convex_distance(*cold_copies.back(), b, b_in_a);
      for (const ConvexDistance& d : {warm, cold}) {
        ASSERT_FALSE(d.intersecting);
        EXPECT_LE(d.lower_bound, truth * (1 + 1e-15));
        EXPECT_NEAR(d.lower_bound, truth, 1e-12 + 1e-9 * truth);
        EXPECT_NEAR(d.distance, truth, 1e-12 + 1e-9 * truth);
      }
      // The same bits either way: an answer never depends on what the thread asked before.
      EXPECT_EQ(warm.distance, cold.distance);
      EXPECT_EQ(warm.lower_bound, cold.lower_bound);
      EXPECT_EQ(warm.on_a, cold.on_a);
      EXPECT_EQ(warm.on_b, cold.on_b);
      if (step > 0) warm_queries += warm.support_queries, cold_queries += cold.support_queries, ++asked;
    }
  }
  ASSERT_GT(asked, 100 * sweeps);
  EXPECT_LT(2 * warm_queries, cold_queries) << "warm " << warm_queries << ", cold " << cold_queries << " over " << asked;
}

TEST(ConvexDistance, EmptyHullsAreInfinitelyFar) {
  const ConvexDistance d = convex_distance(ConvexHull{}, convex_hull(random_cloud(10, 1.0)), Transform::Identity());
  EXPECT_TRUE(std::isinf(d.lower_bound));
}

}  // namespace
}  // namespace bvh_collision
