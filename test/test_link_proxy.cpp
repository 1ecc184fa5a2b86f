// Bounded-error link proxies (narrowphase/link_proxy.h), checked independently of how they were
// built: (a) every vertex, a dense grid of points on every triangle and a grid of points inside
// the solid lie in some leaf sphere (brute force over the leaves); (b) every leaf sphere's centre
// and 200 points of its boundary (where a ball's farthest point from a set lies) are within the
// proven bound, at most level / 2, of the link: distance by brute force over every triangle (or
// the primitive's closest point), zero inside the solid; (c) every inner sphere holds its
// subtree's leaves; (d) proxies_overlap equals brute force over all leaf pairs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <random>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/narrowphase/link_proxy.h"
#include "bvh_collision/narrowphase/proxy_octree.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/geometry/distance.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

// Under the sanitizers (ten times slower, and looking for memory errors, not geometry) the
// proxies are built at the 20 mm level only.
const std::vector<double> kLevels = test::sanitized() ? std::vector<double>{0.02} : std::vector<double>{0.02, 0.01};

std::vector<ProxySphere> leaves(const LinkProxy& p) {
  std::vector<ProxySphere> out;
  for (std::size_t i = 0; i < p.spheres().size(); ++i) {
    if (p.spheres()[i].skip == static_cast<std::int32_t>(i + 1)) out.push_back(p.spheres()[i]);
  }
  return out;
}

bool covered(const std::vector<ProxySphere>& spheres, const Vec3& p) {
  for (const ProxySphere& s : spheres) {
    if ((p - s.center).norm() <= s.radius * (1.0 + 1e-12) + 1e-12) return true;
  }
  return false;
}

// Points on the unit sphere, evenly spread (Fibonacci).
std::vector<Vec3> directions(int n) {
  std::vector<Vec3> out;
  for (int i = 0; i < n; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / n, r = std::sqrt(1.0 - z * z), phi = i * 2.399963229728653;
    out.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return out;
}

void check_tree(const LinkProxy& p) {
  const auto& s = p.spheres();
  for (std::size_t i = 0; i < s.size(); ++i) {
    for (std::int32_t k = static_cast<std::int32_t>(i) + 1; k < s[i].skip; ++k) {
      if (s[k].skip != k + 1) continue;  // an inner sphere holds the leaves of its subtree
      EXPECT_LE((s[k].center - s[i].center).norm() + s[k].radius, s[i].radius * (1 + 1e-12) + 1e-12) << i << " " << k;
    }
  }
}

// One closed mesh as a link: (a), (b), (c).
void check_mesh_proxy(const TriangleMesh& mesh, double level) {
  const Bvh<Obb> bvh = Bvh<Obb>::build(mesh);
  const bool solid = bvh.closed();  // an open mesh is its surface: no interior points
  const LinkProxy proxy = LinkProxy::build({BodyShape{ShapeRef{&bvh, nullptr, Primitive{}}, Transform()}}, level);
  ASSERT_FALSE(proxy.empty());
  EXPECT_LE(proxy.hausdorff_bound(), 0.5 * level);
  check_tree(proxy);
  const std::vector<ProxySphere> ls = leaves(proxy);
  EXPECT_EQ(ls.size(), proxy.leaf_count());
  // (a) the surface (grid of 1 mm or 8 per edge) and the solid (a 4 mm grid).
  std::size_t missed = 0, points = 0;
  for (const auto& t : mesh.triangles) {
    const Vec3 a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const int k = std::clamp(static_cast<int>(std::max({(b - a).norm(), (c - a).norm()}) / 0.001), 8, 64);
    for (int i = 0; i <= k; ++i) {
      for (int j = 0; i + j <= k; ++j) {
        ++points;
        missed += !covered(ls, a + (b - a) * i / k + (c - a) * j / k);
      }
    }
  }
  Vec3 lo = mesh.vertices[0], hi = lo;
  for (const Vec3& v : mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  for (double x = lo.x(); x <= hi.x(); x += 0.004) {
    for (double y = lo.y(); y <= hi.y(); y += 0.004) {
      for (double z = lo.z(); z <= hi.z(); z += 0.004) {
        if (solid && contains_point(bvh, Vec3(x, y, z))) ++points, missed += !covered(ls, Vec3(x, y, z));
      }
    }
  }
  EXPECT_EQ(missed, 0u) << "of " << points << " points of the link";
  // (b) brute-force distance from sphere points to the solid (50 directions a sphere under the
  // sanitizers, whose exact point-triangle distances run instrumented).
  double worst = 0.0;
  const std::vector<Vec3> dirs = directions(test::sanitized() ? 50 : 200);
  for (const ProxySphere& s : ls) {
    std::vector<Vec3> probe{s.center};
    for (const Vec3& d : dirs) probe.push_back(s.center + s.radius * d);
    for (const Vec3& p : probe) {
      if (solid && contains_point(bvh, p)) continue;
      double d = std::numeric_limits<double>::infinity();
      for (const auto& t : mesh.triangles) {
        d = std::min(d, (p - closest_point_on_triangle(p, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]])).norm());
      }
      worst = std::max(worst, d);
    }
  }
  EXPECT_LE(worst, proxy.hausdorff_bound() + 1e-12) << "level " << level;
  std::printf("level %.0f mm: %zu leaves, %zu points covered, farthest sphere point %.3f mm (bound %.3f mm)\n",
              level * 1e3, ls.size(), points, worst * 1e3, proxy.hausdorff_bound() * 1e3);
}

TEST(LinkProxy, PandaHandAndFingerAreCoveredWithinTheBound) {
  const std::string dir = "panda/moveit_resources_panda_description/meshes/collision/";
  for (const double level : kLevels) {
    check_mesh_proxy(test::robot_mesh(dir + "finger.stl"), level);
    check_mesh_proxy(test::robot_mesh(dir + "hand.stl"), level);
  }
}

// An open mesh bounds no solid: its proxy covers the surface alone, every sphere within the bound
// of the surface.
TEST(LinkProxy, OpenMeshIsCoveredAsASurface) {
  TriangleMesh hand = test::robot_mesh("panda/moveit_resources_panda_description/meshes/collision/hand.stl");
  hand.triangles.resize(hand.triangles.size() - 3);
  ASSERT_FALSE(Bvh<Obb>::build(hand).closed());
  check_mesh_proxy(hand, 0.02);
}

TEST(LinkProxy, PrimitivesAreCoveredWithinTheBound) {
  const Primitive prims[] = {Primitive::box(Vec3(0.1, 0.04, 0.2)), Primitive::cylinder(0.03, 0.15),
                             Primitive::capsule(0.02, 0.1), Primitive::sphere(0.05)};
  for (const Primitive& prim : prims) {
    std::vector<BodyShape> shapes(1);
    shapes[0].shape.primitive = prim;
    shapes[0].origin = Transform{Eigen::AngleAxisd(0.3, Vec3(1, 2, 3).normalized()).toRotationMatrix(), Vec3(0.1, 0, 0)};
    const LinkProxy proxy = LinkProxy::build(shapes, 0.01);
    check_tree(proxy);
    const std::vector<ProxySphere> ls = leaves(proxy);
    const Transform to_shape = shapes[0].origin.inverse();
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> u(-1, 1);
    const Vec3 half = half_extents(prim);
    std::size_t missed = 0;
    for (int i = 0; i < 20000; ++i) {  // points of the solid, surface points among them
      Vec3 p(u(rng) * half.x(), u(rng) * half.y(), u(rng) * half.z());
      if (i % 2) p = closest_point(prim, 2.0 * p);
      if (contains(prim, p)) missed += !covered(ls, shapes[0].origin * p);
    }
    EXPECT_EQ(missed, 0u) << primitive_name(prim.kind);
    double worst = 0.0;
    for (const ProxySphere& s : ls) {
      for (const Vec3& d : directions(200)) {
        const Vec3 p = to_shape * (s.center + s.radius * d);
        worst = std::max(worst, (p - closest_point(prim, p)).norm());
      }
    }
    EXPECT_LE(worst, proxy.hausdorff_bound() + 1e-12) << primitive_name(prim.kind);
    EXPECT_LE(proxy.hausdorff_bound(), 0.005);
  }
}

// The build's work, counted on a large mesh (a bumpy sphere of 30,000 triangles, 0.3 m across):
// every cube and surface piece asks a bounded number of spheres (a scan of every sphere chosen,
// as the first build did, asked hundreds of thousands per piece here), every query of the mesh
// opens a number of BVH volumes that grows with the log of its triangles, and halving the level
// (four times the leaves) multiplies the work by about four, not sixteen: n log n of the leaves.
TEST(LinkProxy, BuildWorkGrowsAsNLogNOfTheLeaves) {
  std::mt19937_64 random(3);
  const int rings = test::sanitized() ? 62 : 123;  // a quarter of the triangles under the sanitizers
  const TriangleMesh mesh = test::bumpy_sphere(random, 0.15, rings, rings, 0.02);
  const Bvh<Obb> bvh = Bvh<Obb>::build(mesh);
  ASSERT_TRUE(bvh.closed());
  ASSERT_GT(mesh.triangles.size(), test::sanitized() ? 7000u : 30000u);
  const std::vector<BodyShape> shapes{BodyShape{ShapeRef{&bvh, nullptr, Primitive{}}, Transform()}};
  const double coarse = test::sanitized() ? 0.02 : 0.01;
  std::vector<ProxyBuildStats> work;
  for (const double level : {coarse, coarse / 2}) {
    ProxyBuildStats stats;
    const LinkProxy proxy = LinkProxy::build(shapes, level, &stats);
    ASSERT_EQ(stats.leaves, proxy.leaf_count());
    const double steps = static_cast<double>(stats.cubes + stats.surface_pieces);
    const double queries = static_cast<double>(stats.distance_queries + stats.inside_queries);
    std::printf("level %.0f mm: %zu leaves, %zu cubes, %zu pieces, %zu sphere tests (%.1f a step), %zu queries opening %zu "
                "volumes (%.1f a query), %zu kept-triangle tests, %zu candidates\n",
                level * 1e3, stats.leaves, stats.cubes, stats.surface_pieces, stats.sphere_tests, stats.sphere_tests / steps,
                stats.distance_queries + stats.inside_queries, stats.bvh_volume_tests, stats.bvh_volume_tests / queries,
                stats.triangle_tests, stats.candidates);
    EXPECT_LE(stats.sphere_tests, 40.0 * steps) << "level " << level;
    EXPECT_LE(stats.bvh_volume_tests, 8.0 * std::log2(static_cast<double>(mesh.triangles.size())) * queries) << "level " << level;
    EXPECT_LE(stats.triangle_tests, 64.0 * steps) << "a kept list holds at most 64 triangles";
    work.push_back(stats);
  }
  const double leaves = static_cast<double>(work[1].leaves) / work[0].leaves;
  auto total = [](const ProxyBuildStats& s) {
    return static_cast<double>(s.cubes + s.surface_pieces + s.sphere_tests + s.distance_queries + s.inside_queries +
                               s.bvh_volume_tests + s.triangle_tests);
  };
  const double growth = total(work[1]) / total(work[0]);
  std::printf("halving the level: %.2f times the leaves, %.2f times the work\n", leaves, growth);
  EXPECT_GT(leaves, 2.5);
  EXPECT_LE(growth, 1.5 * leaves * std::log2(static_cast<double>(work[1].leaves)) / std::log2(static_cast<double>(work[0].leaves)));
}

// Panda's finger at 10 mm and its hand at 20 mm (trees of different sizes).
struct FingerAndHand {
  const std::string dir = "panda/moveit_resources_panda_description/meshes/collision/";
  const Bvh<Obb> finger = Bvh<Obb>::build(test::robot_mesh(dir + "finger.stl"));
  const Bvh<Obb> hand = Bvh<Obb>::build(test::robot_mesh(dir + "hand.stl"));
  const LinkProxy finger_proxy = LinkProxy::build({BodyShape{ShapeRef{&finger, nullptr, Primitive{}}, Transform()}}, 0.01);
  const LinkProxy hand_proxy = LinkProxy::build({BodyShape{ShapeRef{&hand, nullptr, Primitive{}}, Transform()}}, 0.02);
};

// Over the same tree on both sides and over trees of different sizes (the walk opens the larger
// sphere of a pair: both sides get opened, and a leaf meets an inner sphere).
TEST(LinkProxy, OverlapEqualsBruteForceOverLeafPairs) {
  const FingerAndHand proxies;
  const LinkProxy& finger_proxy = proxies.finger_proxy;
  const LinkProxy& hand_proxy = proxies.hand_proxy;
  for (const LinkProxy* other : {&finger_proxy, &hand_proxy}) {
    const std::vector<ProxySphere> la = leaves(finger_proxy), lb = leaves(*other);
    std::mt19937_64 rng(9);
    const double extent = other == &hand_proxy ? 0.15 : 0.06;
    std::uniform_real_distribution<double> u(-extent, extent);
    int overlaps = 0;
    for (int i = 0; i < test::sized(400); ++i) {
      const Transform pa = test::random_rotation(rng, Vec3(u(rng), u(rng), u(rng)));
      const Transform pb = test::random_rotation(rng, Vec3(u(rng), u(rng), u(rng)));
      const double padding = i % 3 == 0 ? 0.005 : 0.0;
      bool brute = false;
      for (const ProxySphere& a : la) {
        for (const ProxySphere& b : lb) {
          brute = brute || ((pa * a.center) - (pb * b.center)).norm() <= a.radius + b.radius + padding;
        }
      }
      EXPECT_EQ(proxies_overlap(finger_proxy, pa, *other, pb, padding), brute) << i;
      EXPECT_EQ(proxies_overlap(*other, pb, finger_proxy, pa, padding), brute) << i;
      overlaps += brute;
    }
    EXPECT_GT(overlaps, 0);
    EXPECT_LT(overlaps, test::sized(400));
  }
}

// A witness (the leaf pair that last met) changes no answer: along a walk of small steps (where it
// is mostly still met), with indices that are not a leaf pair of these proxies, and with one from
// the other proxy; a true answer leaves in it a leaf pair that meets (brute force).
TEST(LinkProxy, AWitnessChangesNoAnswerAndHoldsALeafPairThatMeets) {
  const FingerAndHand proxies;
  const LinkProxy& finger_proxy = proxies.finger_proxy;
  const LinkProxy& hand_proxy = proxies.hand_proxy;
  const auto& sf = finger_proxy.spheres();
  const auto& sh = hand_proxy.spheres();
  std::int32_t inner = 0;  // a sphere of the hand's that is not a leaf
  while (sh[inner].skip == inner + 1) ++inner;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> step(-0.01, 0.01);
  Transform pa = test::random_rotation(rng), pb = test::random_rotation(rng, Vec3(0.02, 0.0, 0.0));
  ProxyWitness carried;
  // Every step, sanitized builds too: the walk starts in contact and drifts out of it only after a
  // few hundred steps (the first 150, a sanitized build's quarter, overlapped in 140).
  constexpr int kSteps = 600;
  int overlaps = 0, witness_met = 0;
  for (int i = 0; i < kSteps; ++i) {
    // A small turn and shift of the finger each step: the walk drifts in and out of contact.
    const Vec3 axis = Vec3(step(rng), step(rng), step(rng)).normalized();
    pa.R = Mat3(Eigen::AngleAxisd(0.05, axis)) * pa.R;
    pa.t = Vec3(std::clamp(pa.t[0] + step(rng), -0.15, 0.15), std::clamp(pa.t[1] + step(rng), -0.15, 0.15),
                std::clamp(pa.t[2] + step(rng), -0.15, 0.15));
    bool brute = false;
    for (const ProxySphere& a : leaves(finger_proxy)) {
      for (const ProxySphere& b : leaves(hand_proxy)) brute = brute || ((pa * a.center) - (pb * b.center)).norm() <= a.radius + b.radius;
    }
    const ProxyWitness before = carried;
    const bool with = proxies_overlap(finger_proxy, pa, hand_proxy, pb, 0.0, &carried);
    EXPECT_EQ(with, brute) << i;
    if (with) {
      ASSERT_GE(carried.a, 0);
      ASSERT_GE(carried.b, 0);
      const ProxySphere& a = sf[carried.a];
      const ProxySphere& b = sh[carried.b];
      EXPECT_EQ(a.skip, carried.a + 1) << "a leaf of the finger's";
      EXPECT_EQ(b.skip, carried.b + 1) << "a leaf of the hand's";
      EXPECT_LE(((pa * a.center) - (pb * b.center)).norm(), a.radius + b.radius + 1e-9) << i;
      witness_met += before.a == carried.a && before.b == carried.b;
    }
    overlaps += brute;
    for (ProxyWitness junk : {ProxyWitness{-7, 3}, ProxyWitness{1 << 28, 0}, ProxyWitness{0, inner},
                              ProxyWitness{static_cast<std::int32_t>(sf.size()), static_cast<std::int32_t>(sh.size())},
                              ProxyWitness{carried.b, carried.a}}) {
      EXPECT_EQ(proxies_overlap(finger_proxy, pa, hand_proxy, pb, 0.0, &junk), brute) << i;
    }
  }
  std::printf("%d of %d steps overlap, %d kept the witness they began with\n", overlaps, kSteps, witness_met);
  EXPECT_GT(overlaps, kSteps / 10);
  EXPECT_LT(overlaps, kSteps * 9 / 10);
  EXPECT_GT(witness_met, 0);
}

// The same for a link against an obstacle (a ball here): the witness leaf is asked first, and an
// answer is that of the walk without it, brute force over the leaves.
TEST(LinkProxy, AnObstacleWitnessChangesNoAnswer) {
  const FingerAndHand proxies;
  const LinkProxy& hand = proxies.hand_proxy;
  const std::vector<ProxySphere> hand_leaves = leaves(hand);
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> step(-0.01, 0.01);
  const double ball = 0.06;  // the obstacle: a ball at the origin
  Transform pose = test::random_rotation(rng, Vec3(0.05, 0.0, 0.0));
  std::int32_t carried = -1;
  int overlaps = 0, kept = 0;
  constexpr int kSteps = 600;
  for (int i = 0; i < kSteps; ++i) {
    pose.R = Mat3(Eigen::AngleAxisd(0.05, Vec3(step(rng), step(rng), step(rng)).normalized())) * pose.R;
    pose.t = Vec3(std::clamp(pose.t[0] + step(rng), -0.1, 0.1), std::clamp(pose.t[1] + step(rng), -0.1, 0.1),
                  std::clamp(pose.t[2] + step(rng), -0.1, 0.1));
    const double padding = i % 3 == 0 ? 0.005 : 0.0;
    const double grow = padding + proxy_pose_margin(hand, pose);
    auto meets = [ball](const Vec3& c, double r, bool) { return c.norm() <= ball + r; };
    bool brute = false;
    for (const ProxySphere& leaf : hand_leaves) brute = brute || meets(pose * leaf.center, leaf.radius + grow, true);
    const std::int32_t before = carried;
    const bool with = proxy_meets_obstacle(hand, pose, padding, meets, &carried);
    EXPECT_EQ(with, brute) << i;
    if (with) {
      ASSERT_GE(carried, 0);
      const ProxySphere& leaf = hand.spheres()[carried];
      EXPECT_EQ(leaf.skip, carried + 1) << "a leaf";
      EXPECT_TRUE(meets(pose * leaf.center, leaf.radius + grow, true)) << i;
      kept += before == carried;
    }
    overlaps += brute;
    for (std::int32_t junk : {-4, 0, static_cast<std::int32_t>(hand.spheres().size()), 1 << 29}) {
      EXPECT_EQ(proxy_meets_obstacle(hand, pose, padding, meets, &junk), brute) << i;
    }
    EXPECT_EQ(proxy_meets_obstacle(hand, pose, padding, meets), brute) << i;
  }
  std::printf("%d of %d steps meet the ball, %d kept the witness they began with\n", overlaps, kSteps, kept);
  EXPECT_GT(overlaps, kSteps / 10);
  EXPECT_LT(overlaps, kSteps * 9 / 10);
  EXPECT_GT(kept, 0);
}

// The self check through the proxies keeps docs/design.md's contract against the exact check, on
// panda's uniform random states and on the near-contact ones among them (exact distance under
// 4 cm): no false negative, and every collision it reports is within padding + tolerance.
TEST(LinkProxy, SelfCheckAtToleranceKeepsTheContract) {
  const std::vector<double> paddings = test::sanitized() ? std::vector<double>{0.005} : std::vector<double>{0.0, 0.005};
  for (const double padding : paddings) {
    CheckerOptions exact_options, proxy_options;
    exact_options.padding = proxy_options.padding = padding;
    proxy_options.proxy_levels = kLevels;
    proxy_options.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
    const CollisionChecker exact = test::load_checker("panda", exact_options);
    const CollisionChecker proxied = test::load_checker("panda", proxy_options);
    ASSERT_EQ(proxied.accelerators().proxy_levels().size(), kLevels.size());
    EXPECT_EQ(proxied.accelerators().proxies_for(0.009), nullptr);
    EXPECT_EQ(proxied.accelerators().proxies_for(0.5)->level, 0.02);
    if (kLevels.size() > 1) {
      EXPECT_EQ(proxied.accelerators().proxies_for(0.015)->level, 0.01);
    }
    std::mt19937_64 rng(11);
    int near = 0, collide = 0;
    std::map<double, int> false_positives;
    for (int i = 0; i < test::sized(2000); ++i) {
      const std::vector<double> q = random_configuration(exact.model(), rng);
      SelfCollisionRequest request;
      request.distance = true;
      const SelfCollisionResult truth = exact.check_self(q.data(), request);
      const double d = truth.collision ? 0.0 : truth.min_distance;
      near += d > 0.0 && d < 0.04;
      collide += truth.collision;
      for (const double t : {0.01, 0.015, 0.02, 0.03}) {
        SelfCollisionRequest at;
        at.tolerance = t;
        const bool answer = proxied.check_self(q.data(), at).collision;
        if (truth.collision) {
          EXPECT_TRUE(answer) << "a false negative at tolerance " << t << ", state " << i;
        }
        if (answer) {
          EXPECT_LE(d, 2.0 * padding + t + 1e-9) << "tolerance " << t << ", state " << i;
        }
        false_positives[t] += answer && !truth.collision;
      }
    }
    EXPECT_GT(near, test::sized(2000) / 20);
    EXPECT_GT(collide, test::sized(2000) / 20);
    std::printf("padding %.3f: %d colliding, %d within 4 cm; proxy false positives at 10/15/20/30 mm: %d %d %d %d\n",
                padding, collide, near, false_positives[0.01], false_positives[0.015], false_positives[0.02],
                false_positives[0.03]);
  }
}

// A link's proxy level against the octree with its distance field (narrowphase/proxy_octree.h),
// against the exact mesh-octree distance: a miss proves the mesh farther than the padding, a hit
// puts it within padding + level / 2 (the leaves' Hausdorff bound), and a contact asked for is an
// occupied leaf of the tree with a point of a grown leaf ball on its cube.
TEST(ProxyOctree, AMissIsApartAndAHitWithinHalfTheLevel) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Octree tree(0.02);
  std::vector<ScanPoint> table;  // a table top and a post on it
  for (double x = -0.3; x <= 0.3; x += 0.01) {
    for (double y = -0.3; y <= 0.3; y += 0.01) table.emplace_back(float(x), float(y), 0.0f);
  }
  for (double z = 0.0; z <= 0.3; z += 0.01) table.emplace_back(0.05f, 0.05f, float(z));
  insert_points(tree, table);
  const OctreeDistanceField field = OctreeDistanceField::build(tree, Vec3(-0.5, -0.5, -0.3), Vec3(0.5, 0.5, 0.5), 0.2);
  const Bvh<Obb> bvh = Bvh<Obb>::build(test::bumpy_sphere(rng, 0.06, 8, 10, 0.1));
  int hits = 0, misses = 0, near_misses = 0;
  for (const double level : {0.01, 0.02}) {
    const LinkProxy proxy = LinkProxy::build({BodyShape{ShapeRef{&bvh, nullptr, Primitive{}}, Transform()}}, level);
    for (int i = 0; i < test::sized(600); ++i) {
      const Transform pose = test::random_rotation(rng, Vec3(0.25 * u(rng), 0.25 * u(rng), 0.02 + 0.12 * std::abs(u(rng))));
      const double padding = i % 3 == 0 ? 0.0 : 0.01;
      const double d = mesh_octree_distance(bvh, pose, tree, true).distance;
      const ProxyOctreeHit boolean = proxy_meets_octree(proxy, pose, padding, tree, field, false);
      const ProxyOctreeHit asked = proxy_meets_octree(proxy, pose, padding, tree, field, true);
      ASSERT_EQ(boolean.hit, asked.hit) << i;
      if (!asked.hit) {
        ASSERT_GT(d, padding) << "a miss within the padding: " << i;
        ++misses;
        near_misses += d < padding + level;
        continue;
      }
      ++hits;
      ASSERT_LE(d, padding + proxy.hausdorff_bound() + 1e-9) << "a hit beyond half the level: " << i;
      ASSERT_TRUE(asked.contact.has_value()) << i;
      const Octree::Leaf& cube = asked.contact->voxel;
      const std::optional<Octree::Lookup> found = tree.find(cube.key);
      ASSERT_TRUE(found.has_value()) << i;
      EXPECT_EQ(found->depth, cube.depth);
      EXPECT_TRUE(tree.occupied(found->log_odds)) << "the contact's cube is occupied";
      const Vec3 lo = tree.cube_min(cube.key), hi = lo + Vec3::Constant(tree.cube_size(cube.depth));
      EXPECT_LE((asked.contact->position.cwiseMax(lo).cwiseMin(hi) - asked.contact->position).norm(), 1e-12) << "on the cube";
    }
  }
  std::cout << hits << " hits, " << misses << " misses (" << near_misses << " of them within the level)\n";
  EXPECT_GT(hits, test::sized(600) / 10);
  EXPECT_GT(misses, test::sized(600) / 10);
}

}  // namespace
}  // namespace bvh_collision
