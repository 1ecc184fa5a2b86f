// BVHs against brute force: every volume type x every builder finds exactly the colliding
// triangle pairs and the minimum distance that an all-pairs search finds, on random meshes and on
// real link meshes, over near-contact poses; tolerance never gives a false negative; solids.
#include <gtest/gtest.h>

#include <algorithm>
#include <set>

#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

using test::brute_force_distance;
using test::brute_force_pairs;
using test::near_contact_pose;

std::mt19937_64& rng() {
  static std::mt19937_64 r(7);
  return r;
}

constexpr BuildMethod kMethods[] = {BuildMethod::kTopDownMedian, BuildMethod::kSah, BuildMethod::kBottomUp};

// Pairs of meshes to test on: random closed meshes, a soup, and real link meshes when present.
// Poses and brute-force answers are computed once and shared by every volume type.
struct MeshPair {
  std::string name;
  TriangleMesh a, b;
  std::vector<Transform> poses;                          // b in a's frame, near contact
  std::vector<std::vector<std::pair<int, int>>> pairs;   // brute-force colliding pairs per pose
  std::vector<double> distances;                         // brute-force distance, first kDistancePoses
};
const int kPoses = test::sized(250);  // a quarter under the sanitizers
constexpr int kDistancePoses = 16;

MeshPair make_pair(std::string name, TriangleMesh a, TriangleMesh b) {
  MeshPair mp{std::move(name), std::move(a), std::move(b), {}, {}, {}};
  const auto guide_a = Bvh<Aabb>::build(mp.a), guide_b = Bvh<Aabb>::build(mp.b);
  for (int p = 0; p < kPoses; ++p) {
    mp.poses.push_back(near_contact_pose(rng(), guide_a, guide_b));
    if (p % 8 == 7) mp.poses.back().t += Vec3(0.1, -0.05, 0.08);  // a few far apart too
    auto pairs = brute_force_pairs(mp.a, mp.b, mp.poses.back());
    std::sort(pairs.begin(), pairs.end());
    mp.pairs.push_back(std::move(pairs));
    if (p < kDistancePoses) mp.distances.push_back(brute_force_distance(mp.a, mp.b, mp.poses.back()));
  }
  return mp;
}

const std::vector<MeshPair>& mesh_pairs() {
  static const std::vector<MeshPair> pairs = [] {
    std::vector<MeshPair> out;
    out.push_back(make_pair("bumpy spheres", test::bumpy_sphere(rng(), 0.1, 10, 16, 0.15), test::bumpy_sphere(rng(), 0.06, 8, 12, 0.3)));
    out.push_back(make_pair("soups", test::triangle_soup(rng(), 150, 0.2, 0.03), test::triangle_soup(rng(), 120, 0.15, 0.05)));
    if (std::filesystem::is_directory(test::robots_dir())) {
      const std::string panda = "panda/moveit_resources_panda_description/meshes/collision/";
      out.push_back(make_pair("panda link3/link4", test::robot_mesh(panda + "link3.stl"), test::robot_mesh(panda + "link4.stl")));
      out.push_back(make_pair("panda hand/finger", test::robot_mesh(panda + "hand.stl"), test::robot_mesh(panda + "finger.stl")));
    }
    return out;
  }();
  return pairs;
}

// A box of `size` centred at `at`, its triangles facing out (or in: a cavity's shell).
TriangleMesh shell(const Vec3& size, const Vec3& at, bool inward) {
  TriangleMesh m = box_mesh(size);
  for (Vec3& v : m.vertices) v += at;
  if (inward) {
    for (auto& t : m.triangles) std::swap(t[1], t[2]);
  }
  return m;
}

// Two meshes as one.
TriangleMesh join(TriangleMesh a, const TriangleMesh& b) {
  const auto offset = static_cast<std::int32_t>(a.vertices.size());
  a.vertices.insert(a.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto t : b.triangles) a.triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  return a;
}

template <class BV>
class BvhOracle : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::is_directory(test::robots_dir()) && test::running_in_ci()) {
      FAIL() << "robots folder '" << test::robots_dir() << "' missing (CI=true: this is a failure)";
    }
  }
};
using VolumeTypes = ::testing::Types<Aabb, Obb, Sphere, Kdop14, Kdop18, Kdop26, Rss>;
TYPED_TEST_SUITE(BvhOracle, VolumeTypes);

TYPED_TEST(BvhOracle, VolumesContainTheirTriangles) {
  const TriangleMesh mesh = test::bumpy_sphere(rng(), 0.3, 12, 20, 0.2);
  for (BuildMethod method : kMethods) {
    const auto bvh = Bvh<TypeParam>::build(mesh, {method, 4, 64});
    for (const auto& node : bvh.nodes()) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        for (int k = 0; k < 3; ++k) {
          ASSERT_TRUE(contains(node.volume, bvh.triangles()[i][k])) << build_method_name(method);
        }
      }
      if (!node.is_leaf()) {
        EXPECT_EQ(node.count, bvh.nodes()[node.left].count + bvh.nodes()[node.right].count);
      } else {
        EXPECT_LE(node.count, 4);
      }
    }
  }
}

TYPED_TEST(BvhOracle, CollidingPairsEqualBruteForce) {
  int poses = 0, colliding = 0;
  for (const MeshPair& mp : mesh_pairs()) {
    for (BuildMethod m : kMethods) {
      const auto a = Bvh<TypeParam>::build(mp.a, {m}), b = Bvh<TypeParam>::build(mp.b, {m});
      for (std::size_t p = 0; p < mp.poses.size(); ++p, ++poses) {
        const auto& expected = mp.pairs[p];
        colliding += !expected.empty();
        CollisionRequest all;
        all.max_contacts = std::numeric_limits<std::size_t>::max();
        all.solids = false;
        const CollisionResult r = collide(a, Transform(), b, mp.poses[p], all);
        std::vector<std::pair<int, int>> found;
        for (const MeshContact& c : r.contacts) found.push_back({c.triangle_a, c.triangle_b});
        std::sort(found.begin(), found.end());
        ASSERT_EQ(found, expected) << mp.name << ", " << build_method_name(m) << ", pose " << p;
        CollisionRequest boolean;
        boolean.solids = false;
        ASSERT_EQ(collide(a, Transform(), b, mp.poses[p], boolean).collision, !expected.empty());
      }
    }
  }
  EXPECT_GT(colliding, poses / 5) << "poses should be near contact, both ways";
  EXPECT_LT(colliding, poses * 4 / 5);
}

TYPED_TEST(BvhOracle, DistanceEqualsBruteForce) {
  for (const MeshPair& mp : mesh_pairs()) {
    for (BuildMethod m : kMethods) {
      const auto a = Bvh<TypeParam>::build(mp.a, {m}), b = Bvh<TypeParam>::build(mp.b, {m});
      for (std::size_t p = 0; p < mp.distances.size(); ++p) {
        const double expected = mp.distances[p];
        const Transform world = test::random_rotation(rng(), Vec3(0.3, -2.0, 1.0));
        const DistanceResult r = distance(a, world, b, world * mp.poses[p], {});
        ASSERT_NEAR(r.distance, expected, 1e-9 * expected + 1e-15) << mp.name << ", " << build_method_name(m);
        // Witnesses: on the two meshes, as far apart as reported.
        ASSERT_NEAR((r.point_a - r.point_b).norm(), r.distance, 1e-12);
        const Triangle ta = mp.a.triangle(r.triangle_a), tb = mp.b.triangle(r.triangle_b);
        const Vec3 pa = world.inverse() * r.point_a, pb = (world * mp.poses[p]).inverse() * r.point_b;
        ASSERT_LT((closest_point_on_triangle(pa, ta[0], ta[1], ta[2]) - pa).norm(), 1e-12);
        ASSERT_LT((closest_point_on_triangle(pb, tb[0], tb[1], tb[2]) - pb).norm(), 1e-12);
      }
    }
  }
}

// A point against a mesh: the distance the BVH finds is the smallest over every triangle, with
// or without an upper bound, and point_within answers "closer than r" as that minimum does, for
// points inside, on and around bumpy closed meshes and real link meshes, posed.
TYPED_TEST(BvhOracle, PointDistanceAndWithinEqualBruteForce) {
  std::mt19937_64 random(11);  // its own: the shared one's draws are the other tests'
  std::vector<TriangleMesh> meshes{test::bumpy_sphere(random, 0.1, 10, 16, 0.15), test::triangle_soup(random, 150, 0.2, 0.03)};
  for (const MeshPair& mp : mesh_pairs()) meshes.push_back(mp.a);
  std::uniform_real_distribution<double> u(-1.0, 1.0), scale(0.0, 1.6);
  int within = 0, queries = 0;
  for (const TriangleMesh& mesh : meshes) {
    const auto bvh = Bvh<TypeParam>::build(mesh);
    const Vec3 centre = center(bvh.root().volume);
    const double size = radius(bvh.root().volume);
    const Transform pose{Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix(), Vec3(0.3, -0.2, 0.5)};
    for (int i = 0; i < test::sized(400); ++i, ++queries) {
      const Vec3 local = centre + scale(random) * size * Vec3(u(random), u(random), u(random)).normalized();
      double brute = std::numeric_limits<double>::infinity();
      for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Triangle tri = mesh.triangle(t);
        brute = std::min(brute, (closest_point_on_triangle(local, tri[0], tri[1], tri[2]) - local).norm());
      }
      const Vec3 p = pose * local;
      const DistanceResult d = point_distance(bvh, pose, p);
      ASSERT_NEAR(d.distance, brute, 1e-12 * (1.0 + size)) << "mesh " << &mesh - meshes.data() << ", point " << i;
      ASSERT_NEAR((d.point_b - p).norm(), d.distance, 1e-12 * (1.0 + size));
      const double r = brute * (i % 2 == 0 ? 1.0 + 1e-6 : 1.0 - 1e-6) + (i % 3 == 0 ? 1e-9 : 0.0);
      const bool expected = brute < r;
      within += expected;
      QueryStats stats;
      ASSERT_EQ(point_within(bvh, pose, p, r, &stats), expected) << "point " << i << ", radius " << r << ", nearest " << brute;
      // Every triangle closer than a radius a few times the nearest (the mesh's own frame), and
      // the overflow once there are more than asked for.
      const double wide = 3.0 * brute + 0.01 * size;
      std::vector<int> near_brute;
      for (std::size_t t = 0; t < bvh.triangles().size(); ++t) {
        const Triangle& tri = bvh.triangles()[t];
        if ((closest_point_on_triangle(local, tri[0], tri[1], tri[2]) - local).norm() < wide) near_brute.push_back(static_cast<int>(t));
      }
      std::vector<std::int32_t> near;
      ASSERT_TRUE(triangles_near(bvh, local, wide, near_brute.size(), near));
      std::sort(near.begin(), near.end());
      ASSERT_EQ(std::vector<int>(near.begin(), near.end()), near_brute) << "point " << i;
      if (near_brute.size() > 1) {
        near.clear();
        EXPECT_FALSE(triangles_near(bvh, local, wide, near_brute.size() - 1, near));
        EXPECT_EQ(near.size(), near_brute.size()) << "it stops at the first triangle past the count";
      }
      ASSERT_EQ(point_distance(bvh, pose, p, r).distance < r, expected);
      EXPECT_LE(stats.primitive_tests, mesh.triangles.size());
    }
  }
  EXPECT_GT(within, queries / 4);
  EXPECT_LT(within, 3 * queries / 4);
}

// The winding number a ray cast counts (winding_number) is what contains_point decides by, and
// it can be carried from one point to another by the signed crossings of the segment between
// them (signed_crossing over every triangle): on a bumpy sphere, two overlapping boxes (winding
// 2 where they overlap) and a box with a cavity, for random segments and for segments lying in
// the boxes' face planes (the cases a carried count could get wrong), against the boxes themselves.
TYPED_TEST(BvhOracle, WindingNumbersCarryAlongSegments) {
  std::mt19937_64 random(13);
  const std::vector<TriangleMesh> meshes{test::bumpy_sphere(random, 0.5, 12, 16, 0.2),
                                         join(shell(Vec3(1, 0.6, 0.6), Vec3::Zero(), false), shell(Vec3(1, 0.6, 0.6), Vec3(0.5, 0.1, 0.05), false)),
                                         join(shell(Vec3(1, 1, 1), Vec3::Zero(), false), shell(Vec3(0.4, 0.4, 0.4), Vec3::Zero(), true))};
  std::uniform_real_distribution<double> u(-0.9, 1.2);
  const double planes[] = {0.5, -0.5, 0.3, -0.3, 0.2, -0.2};  // the boxes' face planes
  int carried = 0, inside = 0, twice = 0;
  for (const TriangleMesh& mesh : meshes) {
    const auto bvh = Bvh<TypeParam>::build(mesh);
    ASSERT_TRUE(bvh.closed());
    for (int i = 0; i < test::sized(1500); ++i) {
      Vec3 a(u(random), u(random), u(random)), b(u(random), u(random), u(random));
      if (i % 3 == 1) a.z() = b.z() = planes[i % 6];  // a segment in a face plane
      if (i % 3 == 2) a.x() = planes[i % 6], b = a + Vec3(0.0, u(random), 0.0);
      const std::optional<int> wa = winding_number(bvh, a), wb = winding_number(bvh, b);
      if (wa) {
        ASSERT_EQ(*wa != 0, contains_point(bvh, a)) << a.transpose();
      }
      if (!wa || !wb) continue;
      int w = *wa;
      bool decided = true;
      for (const Triangle& t : bvh.triangles()) {
        const std::optional<int> c = signed_crossing(a, b, t);
        decided = decided && c.has_value();
        if (c) w -= *c;
      }
      if (!decided) continue;
      ASSERT_EQ(w, *wb) << "from " << a.transpose() << " to " << b.transpose();
      ++carried;
      inside += *wb != 0;
      twice += *wb == 2;
    }
  }
  EXPECT_GT(carried, test::sized(1500));
  EXPECT_GT(inside, carried / 20);
  EXPECT_GE(twice, test::sized(20)) << "points in both overlapping boxes (a sanitized run samples a quarter)";
  std::printf("%d segments carried, %d ending inside, %d in both boxes\n", carried, inside, twice);
}

TYPED_TEST(BvhOracle, ToleranceNeverGivesAFalseNegative) {
  const double tolerances[] = {0.0, 0.001, 0.002, 0.005, 0.01, 0.02, 0.05};
  int shortcuts = 0;
  for (const MeshPair& mp : mesh_pairs()) {
    const auto a = Bvh<TypeParam>::build(mp.a), b = Bvh<TypeParam>::build(mp.b);
    for (std::size_t p = 0; p < mp.distances.size(); ++p) {
      const double d = mp.distances[p];
      for (double eps : tolerances) {
        CollisionRequest request;
        request.tolerance = eps;
        request.solids = false;
        const CollisionResult r = collide(a, Transform(), b, mp.poses[p], request);
        if (d == 0.0) {
          ASSERT_TRUE(r.collision) << mp.name << " eps " << eps << ": false negative";
        }
        if (r.collision) {
          ASSERT_LE(d, eps) << mp.name << " eps " << eps << ": reported beyond the tolerance";
        }
        shortcuts += r.within_tolerance;
      }
    }
  }
  // Coarse volumes (spheres) around the random meshes' large triangles have more slack than any
  // tolerance above, so without the robots' meshes no pose above may take the shortcut. Two finely
  // tessellated spheres of radius 0.1 with centres 0.198 apart must take it at 2 cm whatever the
  // volume type. They intersect without a brute-force oracle: the facets lie within 0.2 mm of the
  // true sphere, so a's vertex (0.1, 0, 0) is inside b and a's vertex (-0.1, 0, 0) outside it.
  std::mt19937_64 local(11);
  const TriangleMesh fine = test::bumpy_sphere(local, 0.1, 48, 64, 0.0);
  const auto a = Bvh<TypeParam>::build(fine);
  const Transform overlapping = Transform::Translation(Vec3(0.198, 0.0, 0.0));
  CollisionRequest request;
  request.tolerance = 0.02;
  request.solids = false;
  const CollisionResult r = collide(a, Transform(), a, overlapping, request);
  EXPECT_TRUE(r.collision);
  shortcuts += r.within_tolerance;
  EXPECT_GT(shortcuts, 0) << "the tolerance never took effect";
}

// Every node's slack bounds the distance from any point of its volume to its own triangles:
// random points of each volume's enclosing box (which holds the volume), against the brute-force
// distance to the node's triangles. A mesh under 50k triangles takes the sampled bounds; one
// over it (built on two threads) the corner and composed bounds only: both must hold everywhere.
TYPED_TEST(BvhOracle, SlackBoundsEveryNode) {
  std::mt19937_64 rng(23);
  // Under the sanitizers the small mesh only: building the large one for seven volume types was
  // a minute there (Limits.LargeMeshLoadsInSeconds builds a 99k-triangle mesh under them).
  for (const auto& [rings, segments] : {std::pair{24, 32}, std::pair{168, 200}}) {
    if (test::sanitized() && rings > 24) continue;
    const TriangleMesh mesh = test::bumpy_sphere(rng, 0.1, rings, segments, 0.002);
    const auto bvh = Bvh<TypeParam>::build(mesh);
    std::uniform_int_distribution<std::size_t> pick(0, bvh.nodes().size() - 1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    int checked = 0;
    for (int k = 0; k < 3000; ++k) {
      const std::size_t i = k < 8 ? static_cast<std::size_t>(k) : pick(rng);  // the top levels too
      const BvhNode<TypeParam>& node = bvh.nodes()[i];
      if (node.count > 4000) continue;
      const EnclosingBox box = enclosing_box(node.volume);
      ASSERT_LE(node.slack, 2.0 * node.size * (1 + 1e-9)) << "node " << i;
      for (int s = 0; s < 4; ++s) {
        const Vec3 p = box.center + box.axes * box.half.cwiseProduct(Vec3(u(rng), u(rng), u(rng)));
        if (!contains(node.volume, p)) continue;
        double d = std::numeric_limits<double>::infinity();
        for (int t = node.first; t < node.first + node.count; ++t) {
          const Triangle& tri = bvh.triangles()[t];
          d = std::min(d, (closest_point_on_triangle(p, tri[0], tri[1], tri[2]) - p).norm());
        }
        ASSERT_LE(d, node.slack) << mesh.triangles.size() << " triangles, node " << i << " of " << node.count;
        ++checked;
      }
    }
    EXPECT_GT(checked, 1000);
  }
}

TYPED_TEST(BvhOracle, PaddingMatchesDistance) {
  const MeshPair& mp = mesh_pairs()[0];
  const auto a = Bvh<TypeParam>::build(mp.a), b = Bvh<TypeParam>::build(mp.b);
  for (std::size_t p = 0; p < mp.distances.size(); ++p) {
    const Transform& pose = mp.poses[p];
    const double d = mp.distances[p];
    for (double padding : {0.001, 0.004}) {
      CollisionRequest request;
      request.padding = padding;
      request.solids = false;
      ASSERT_EQ(collide(a, Transform(), b, pose, request).collision, d <= padding) << "d = " << d;
    }
  }
}

TYPED_TEST(BvhOracle, SolidsContainment) {
  // A small closed box inside a large one: no surfaces touch, yet they collide.
  const auto big = Bvh<TypeParam>::build(box_mesh(Vec3(1, 1, 1)));
  const auto small = Bvh<TypeParam>::build(box_mesh(Vec3(0.1, 0.2, 0.1)));
  ASSERT_TRUE(big.closed());
  const Transform inside = test::random_rotation(rng(), Vec3(0.1, 0.2, -0.15));
  EXPECT_TRUE(collide(big, Transform(), small, inside).collision);
  EXPECT_TRUE(collide(small, inside, big, Transform()).collision);  // either order
  EXPECT_EQ(distance(big, Transform(), small, inside).distance, 0.0);
  CollisionRequest surfaces_only;
  surfaces_only.solids = false;
  EXPECT_FALSE(collide(big, Transform(), small, inside, surfaces_only).collision);
  // Outside, beside it: free.
  const Transform outside = test::random_rotation(rng(), Vec3(0.9, 0.0, 0.0));
  EXPECT_FALSE(collide(big, Transform(), small, outside).collision);
  EXPECT_GT(distance(big, Transform(), small, outside).distance, 0.2);
  // An open mesh (one face removed) bounds no solid.
  TriangleMesh open = box_mesh(Vec3(1, 1, 1));
  open.triangles.pop_back();
  const auto open_bvh = Bvh<TypeParam>::build(open);
  EXPECT_FALSE(open_bvh.closed());
  EXPECT_FALSE(collide(open_bvh, Transform(), small, inside).collision);
}

// A link made of closed shells that overlap (two boxes, as a URDF's mesh often is) is solid in
// the overlap too, and a cavity (an inward-facing inner shell) is not solid: containment is the
// winding number, checked against the boxes themselves. Ray parity called the overlap outside.
TYPED_TEST(BvhOracle, ContainmentIsTheWindingNumber) {
  const Vec3 size(1.0, 0.6, 0.6), at_a(0, 0, 0), at_b(0.5, 0.1, 0.05);
  const auto two = Bvh<TypeParam>::build(join(shell(size, at_a, false), shell(size, at_b, false)));
  const auto hollow = Bvh<TypeParam>::build(join(shell(Vec3(1, 1, 1), at_a, false), shell(Vec3(0.4, 0.4, 0.4), at_a, true)));
  ASSERT_TRUE(two.closed());
  ASSERT_TRUE(hollow.closed());
  auto in_box = [](const Vec3& p, const Vec3& size, const Vec3& at) { return ((p - at).cwiseAbs() - 0.5 * size).maxCoeff() <= 0; };
  std::uniform_real_distribution<double> u(-0.8, 1.3);
  std::mt19937_64 draw(3000);  // its own stream: the same points however the program is filtered
  int overlap = 0, cavity = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p(u(draw), 0.6 * u(draw), 0.6 * u(draw));
    const bool a = in_box(p, size, at_a), b = in_box(p, size, at_b);
    overlap += a && b;
    ASSERT_EQ(contains_point(two, p), a || b) << p.transpose();
    const bool in_cavity = ((p.cwiseAbs() - Vec3::Constant(0.2)).maxCoeff() < 0);
    cavity += in_cavity;
    ASSERT_EQ(contains_point(hollow, p), in_box(p, Vec3(1, 1, 1), at_a) && !in_cavity) << p.transpose();
  }
  EXPECT_GT(overlap, 100);
  EXPECT_GT(cavity, 10);
  // A small box wholly in the overlap collides with the two-shell link (solids).
  const auto small = Bvh<TypeParam>::build(box_mesh(Vec3(0.1, 0.1, 0.1)));
  EXPECT_TRUE(collide(two, Transform(), small, Transform::Translation(Vec3(0.25, 0.05, 0.02))).collision);
}

TYPED_TEST(BvhOracle, EmptyMeshCollidesWithNothing) {
  const auto empty = Bvh<TypeParam>::build(TriangleMesh{});
  const auto box = Bvh<TypeParam>::build(box_mesh(Vec3(1, 1, 1)));
  EXPECT_TRUE(empty.empty());
  EXPECT_FALSE(collide(empty, Transform(), box, Transform()).collision);
  EXPECT_FALSE(collide(box, Transform(), empty, Transform()).collision);
  EXPECT_TRUE(std::isinf(distance(box, Transform(), empty, Transform()).distance));
  EXPECT_FALSE(raycast(empty, Transform(), Vec3::Zero(), Vec3::UnitX(), 10.0).hit);
}

TYPED_TEST(BvhOracle, RaycastEqualsBruteForce) {
  const TriangleMesh mesh = test::bumpy_sphere(rng(), 0.2, 10, 16, 0.2);
  const auto bvh = Bvh<TypeParam>::build(mesh);
  const Transform pose = test::random_rotation(rng(), Vec3(1, 2, 3));
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 300; ++i) {
    const Vec3 origin = pose * Vec3(n(rng()), n(rng()), n(rng())) * 0.3;
    const Vec3 dir = Vec3(n(rng()), n(rng()), n(rng()));
    const RayHit hit = raycast(bvh, pose, origin, dir, 2.0);
    // Brute force in the mesh frame.
    double best = std::numeric_limits<double>::infinity();
    const Vec3 o = pose.inverse() * origin, d = pose.R.transpose() * dir.normalized();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle tri = mesh.triangle(t);
      if (!segment_intersects_triangle(o, o + 2.0 * d, tri[0], tri[1], tri[2])) continue;
      const Vec3 nrm = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
      const double s = (tri[0] - o).dot(nrm) / d.dot(nrm);
      best = std::min(best, s);
    }
    ASSERT_EQ(hit.hit, std::isfinite(best)) << "ray " << i;
    if (hit.hit) {
      ASSERT_NEAR(hit.distance, best, 1e-9);
      ASSERT_NEAR((hit.point - origin).norm(), hit.distance, 1e-9);
    }
  }
}

TYPED_TEST(BvhOracle, AtMostNContactsWithGeometryOnBothMeshes) {
  const MeshPair& mp = mesh_pairs()[0];
  const auto a = Bvh<TypeParam>::build(mp.a), b = Bvh<TypeParam>::build(mp.b);
  int checked = 0;
  for (std::size_t p = 0; p < mp.poses.size() && checked < 20; ++p) {
    const std::size_t total = mp.pairs[p].size();
    if (total < 2) continue;
    ++checked;
    const Transform world = test::random_rotation(rng(), Vec3(1, 2, 3));
    CollisionRequest request;
    request.solids = false;
    request.max_contacts = total - 1;
    const CollisionResult r = collide(a, world, b, world * mp.poses[p], request);
    ASSERT_TRUE(r.collision);
    ASSERT_EQ(r.contacts.size(), total - 1) << "stops at max_contacts";
    for (const MeshContact& contact : r.contacts) {
      // The contact point lies on both triangles (world frame), the normal is a unit vector.
      const Triangle ta = mp.a.triangle(contact.triangle_a), tb = mp.b.triangle(contact.triangle_b);
      const Vec3 pa = world.inverse() * contact.position, pb = (world * mp.poses[p]).inverse() * contact.position;
      EXPECT_LT((closest_point_on_triangle(pa, ta[0], ta[1], ta[2]) - pa).norm(), 1e-9);
      EXPECT_LT((closest_point_on_triangle(pb, tb[0], tb[1], tb[2]) - pb).norm(), 1e-9);
      EXPECT_NEAR(contact.normal.norm(), 1.0, 1e-12);
      EXPECT_GE(contact.depth, 0.0);
    }
  }
  EXPECT_GT(checked, 5);
}

TYPED_TEST(BvhOracle, AnyHitRayAgreesWithFirstHit) {
  const TriangleMesh mesh = test::bumpy_sphere(rng(), 0.2, 10, 16, 0.2);
  const auto bvh = Bvh<TypeParam>::build(mesh);
  std::normal_distribution<double> n(0.0, 1.0);
  int hits = 0;
  for (int i = 0; i < 300; ++i) {
    const Vec3 origin = Vec3(n(rng()), n(rng()), n(rng())) * 0.3, dir(n(rng()), n(rng()), n(rng()));
    const RayHit first = raycast(bvh, Transform(), origin, dir, 0.5);
    const RayHit any = raycast(bvh, Transform(), origin, dir, 0.5, true);
    ASSERT_EQ(any.hit, first.hit);
    if (any.hit) {
      EXPECT_GE(any.distance, first.distance - 1e-12);
      EXPECT_LE(any.distance, 0.5);
    }
    hits += first.hit;
  }
  EXPECT_GT(hits, 15);  // about one ray in ten reaches the mesh within 0.5
}

TEST(BoundingVolumes, SphereBoxTestIsTheExactOne) {
  // The seed's test -- "distance between the centres <= radius" -- against the exact one.
  // A sphere of radius 1 touching the face of a cube of side 10: centres are 6 apart.
  const Vec3 box_min(-5, -5, -5), box_max(5, 5, 5), centre(6, 0, 0);
  const double r = 1.0;
  const bool seed_test = (centre - 0.5 * (box_min + box_max)).norm() <= r;
  EXPECT_FALSE(seed_test) << "the centre-distance test misses this overlap";
  EXPECT_TRUE(sphere_intersects_box(centre, r, box_min, box_max));
  // Near a corner: close to the box in distance of centres terms, yet apart.
  const Vec3 near_corner(5.8, 5.8, 5.8);
  EXPECT_FALSE(sphere_intersects_box(near_corner, 1.0, box_min, box_max));
  // Against a brute-force oracle: sample the sphere densely.
  std::uniform_real_distribution<double> u(-8, 8);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 c(u(rng()), u(rng()), u(rng()));
    const double rr = std::abs(u(rng())) / 2;
    const Vec3 closest = c.cwiseMax(box_min).cwiseMin(box_max);
    EXPECT_EQ(sphere_intersects_box(c, rr, box_min, box_max), (closest - c).norm() <= rr);
  }
}

TEST(BoundingVolumes, MergesContainBothVolumes) {
  for (int i = 0; i < 200; ++i) {
    const TriangleMesh m1 = test::triangle_soup(rng(), 5, 1.0, 0.2), m2 = test::triangle_soup(rng(), 5, 3.0, 0.5);
    const std::vector<Vec3>& p1 = m1.vertices;
    std::vector<Vec3> p2 = m2.vertices;
    for (Vec3& p : p2) p += Vec3(2, 0, 1);
    auto check = [&](auto tag) {
      using BV = decltype(tag);
      const BV merged = merge(fit_volume<BV>(p1.data(), p1.size()), fit_volume<BV>(p2.data(), p2.size()));
      for (const Vec3& p : p1) {
        ASSERT_TRUE(contains(merged, p)) << volume_name<BV>();
      }
      for (const Vec3& p : p2) {
        ASSERT_TRUE(contains(merged, p)) << volume_name<BV>();
      }
    };
    check(Aabb{});
    check(Obb{});
    check(Sphere{});
    check(Kdop14{});
    check(Kdop18{});
    check(Kdop26{});
    check(Rss{});
  }
}

}  // namespace
}  // namespace bvh_collision
