// A mesh against an exact primitive (narrowphase/shape_pairs.h): a dented mesh near a box by
// distance and boolean against CGAL's triangle distances, the booleans the convex hulls settle
// without walking the mesh's tree, and the one hull search a distance takes. One binary with test_environment.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <map>
#include <random>
#include <set>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/convex_distance.h"
#include "bvh_collision/narrowphase/shape_pairs.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "cgal_oracle.h"
#include "fcl_oracle.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

// A mesh's distance to a box (half extents `half`, at box_pose) by CGAL's triangle distances over
// every triangle, nearest bounding box first: one whose bounding box is farther than the best so
// far cannot be nearer, nor can any after it.
double oracle_mesh_box_distance(const TriangleMesh& mesh, const Transform& mesh_pose, const Transform& box_pose, const Vec3& half) {
  std::vector<std::pair<double, Triangle>> local;
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Triangle tri = mesh.triangle(t);
    const Triangle q{{box_pose.inverse() * (mesh_pose * tri[0]), box_pose.inverse() * (mesh_pose * tri[1]),
                      box_pose.inverse() * (mesh_pose * tri[2])}};
    const Vec3 lo = q[0].cwiseMin(q[1]).cwiseMin(q[2]), hi = q[0].cwiseMax(q[1]).cwiseMax(q[2]);
    local.emplace_back((lo - half).cwiseMax(-half - hi).cwiseMax(0.0).norm(), q);
  }
  std::sort(local.begin(), local.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  double truth = std::numeric_limits<double>::infinity();
  for (const auto& [bound, q] : local) {
    if (bound > truth) break;
    truth = std::min(truth, test::cgal_triangle_box_distance(q, -half, half));
  }
  return truth;
}

// A bumpy sphere (dents and bumps of 40 %) as a narrowphase mesh, and a box.
struct DentedMeshAndBox {
  TriangleMesh mesh;
  Bvh<Obb> bvh;
  ConvexHull hull;
  ShapeRef mesh_ref;
  Vec3 half{0.03, 0.05, 0.02};
  ShapeRef box{nullptr, nullptr, Primitive::box(2.0 * half)};
  explicit DentedMeshAndBox(std::mt19937_64& r)
      : mesh(test::bumpy_sphere(r, 0.1, 8, 12, 0.4)), bvh(Bvh<Obb>::build(mesh)), hull(convex_hull(mesh.vertices)), mesh_ref{&bvh, &hull, Primitive{}} {}
  DentedMeshAndBox(const DentedMeshAndBox&) = delete;  // (mesh_ref points into it)
};

// A mesh against a box primitive, by the narrowphase's distance (shape_pairs.h), against CGAL's
// triangle distances over every triangle: a bumpy sphere (dents and bumps of 40 %) at random
// poses, the box often facing a dent, where the mesh's convex hull is nearer than the mesh and its
// closest point is not on the surface (the hull settles a pair only when it is).
TEST(MeshAgainstPrimitive, ADentedMeshAgainstABoxIsExact) {
  std::mt19937_64 r(21);
  const DentedMeshAndBox shapes(r);
  const auto& [mesh, bvh, hull, mesh_ref, half, box] = shapes;
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  int apart = 0, off_hull = 0;
  for (int i = 0; i < test::sized(200); ++i) {
    const Transform mesh_pose = test::random_rotation(r, Vec3(u(r), u(r), u(r)));
    const Transform box_pose = Transform::Translation(Vec3(u(r), u(r), u(r)));
    const double truth = oracle_mesh_box_distance(mesh, mesh_pose, box_pose, half);
    if (truth < 1e-6) continue;  // (the mesh holding the box is another test's)
    ++apart;
    QueryStats stats;
    Vec3 wa, wb;
    const double d = shapes_distance(mesh_ref, mesh_pose, box, box_pose, std::numeric_limits<double>::infinity(), true, wa, wb, stats);
    ASSERT_NEAR(d, truth, 1e-9) << i;
    EXPECT_NEAR((wa - wb).norm(), d, 1e-9) << i;
    const ConvexDistance h = convex_distance(ConvexShape::of(hull), ConvexShape::of(box.primitive), relative_transform(mesh_pose, box_pose));
    off_hull += h.distance < truth - 1e-6;
  }
  std::cout << apart << " poses apart, " << off_hull << " with the hull nearer than the mesh\n";
  EXPECT_GT(apart, test::sized(200) / 4);
  EXPECT_GT(off_hull, apart / 10);  // the dents are met
}

// The boolean of a mesh against a box and against another mesh, near contact (within a few
// centimetres, where the tree walk goes down to triangles): the answer of docs/design.md
// against CGAL's distances (a hit within the padding, none beyond padding and tolerance), and no
// tree walked at all where the convex hulls are proven farther apart than padding and tolerance
// (the mesh lies in its hull); a mesh pair answers as the BVH walk alone. Contacts asked for walk.
TEST(MeshAgainstPrimitive, ABooleanTheHullsSettleWalksNoTree) {
  std::mt19937_64 r(23);
  const DentedMeshAndBox shapes(r);
  const auto& [mesh, bvh, hull, mesh_ref, half, box] = shapes;
  std::uniform_real_distribution<double> u(-0.2, 0.2), near(0.0, 0.03);
  int settled = 0, walked = 0, hits = 0, pairs_settled = 0;
  for (int i = 0; i < test::sized(300); ++i) {
    const Transform mesh_pose = test::random_rotation(r, Vec3(u(r), u(r), u(r)));
    const Transform box_pose = Transform::Translation(Vec3(u(r), u(r), u(r)));
    const double truth = oracle_mesh_box_distance(mesh, mesh_pose, box_pose, half);
    if (truth > 0.05) continue;
    PairRequest request;
    request.padding = near(r);
    request.tolerance = i % 2 ? 0.01 : 0.0;
    const double beyond = request.padding + request.tolerance;
    QueryStats stats;
    const bool hit = shapes_collide(mesh_ref, mesh_pose, box, box_pose, request, nullptr, stats);
    if (truth <= request.padding - 1e-9) {
      ASSERT_TRUE(hit) << i;
    }
    if (truth > beyond + 1e-9) {
      ASSERT_FALSE(hit) << i;
    }
    hits += hit;
    const bool hull_apart = convex_distance(ConvexShape::of(hull), ConvexShape::of(box.primitive), relative_transform(mesh_pose, box_pose), beyond)
                                .lower_bound > beyond;
    if (hull_apart) {
      EXPECT_EQ(stats.volume_tests + stats.primitive_tests, 0u) << i;
      ++settled;
    } else {
      ++walked;
    }
    std::vector<MeshContact> contacts;
    QueryStats walk;
    request.max_contacts = 4;
    EXPECT_EQ(shapes_collide(mesh_ref, mesh_pose, box, box_pose, request, &contacts, walk), hit) << i;
    EXPECT_GT(walk.volume_tests, 0u) << i;
    // The same mesh turned, its centre 0.2-0.3 from the first's (the bumps reach 0.06-0.14): two
    // meshes near contact.
    const Vec3 away = (box_pose.t - mesh_pose.t).normalized() * (0.2 + 0.1 * near(r) / 0.03);
    const Transform other = test::random_rotation(r, mesh_pose.t + away);
    request.max_contacts = 0;
    QueryStats pair_stats;
    const bool pair_hit = shapes_collide(mesh_ref, mesh_pose, mesh_ref, other, request, nullptr, pair_stats);
    CollisionRequest direct;
    direct.padding = request.padding;
    EXPECT_EQ(pair_hit, collide(bvh, mesh_pose, bvh, other, direct).collision || (pair_hit && request.tolerance > 0)) << i;
    pairs_settled += pair_stats.volume_tests == 0;
  }
  std::cout << settled << " booleans settled by the hulls, " << walked << " walked (" << hits << " hits); " << pairs_settled
            << " mesh pairs settled by the hulls\n";
  // (Shares of the poses near contact: test::sized shortens the loop under the sanitizers.)
  const int near_contact = settled + walked;
  EXPECT_GE(settled, near_contact / 5);
  EXPECT_GE(walked, near_contact / 5);
  EXPECT_GE(pairs_settled, near_contact / 10);
  EXPECT_GT(near_contact, test::sized(300) / 10);
}

// One hull search asked for the distance only when it is near (convex_distance's far_only, as a
// mesh's distance to a primitive asks it): above `decide_at` it may stop at once, with a bound
// above it; below, it goes on to within the slack. Against CGAL's exact distance between the
// hull's vertices and a box's corners (or a sphere's centre, less its radius: a curved surface),
// and with fewer support queries than the two searches it replaces (decide, then start again).
TEST(MeshAgainstPrimitive, AFarOnlySearchDecidesAboveAndConvergesBelow) {
  std::mt19937_64 r(27);
  const DentedMeshAndBox shapes(r);
  const ConvexHull& hull = shapes.hull;
  const Vec3 half = shapes.half;
  std::uniform_real_distribution<double> u(-0.25, 0.25), factor(0.5, 1.5);
  const double slack = 1e-5;
  int near = 0, far = 0;
  long one_search = 0, two_searches = 0;
  for (int i = 0; i < test::sized(200); ++i) {
    const bool sphere = i % 2 == 1;
    const Primitive p = sphere ? Primitive::sphere(0.04) : Primitive::box(2.0 * half);
    const Transform mesh_pose = test::random_rotation(r, Vec3(u(r), u(r), u(r)));
    const Transform p_pose = Transform::Translation(Vec3(u(r), u(r), u(r)));
    const Transform p_in_mesh = relative_transform(mesh_pose, p_pose);
    std::vector<Vec3> in_p;
    for (const Vec3& v : hull.vertices) in_p.push_back(p_pose.inverse() * (mesh_pose * v));
    std::vector<Vec3> corners;
    if (sphere) {
      corners.push_back(Vec3::Zero());
    } else {
      for (int c = 0; c < 8; ++c) corners.emplace_back(c & 1 ? half.x() : -half.x(), c & 2 ? half.y() : -half.y(), c & 4 ? half.z() : -half.z());
    }
    const double truth = std::max(0.0, test::cgal_polytope_distance(in_p, corners) - (sphere ? 0.04 : 0.0));
    if (truth < 1e-4) continue;  // (touching is the booleans' test)
    const double decide_at = truth * factor(r);
    const ConvexShape a = ConvexShape::of(hull), b = ConvexShape::of(p);
    const ConvexDistance d = convex_distance(a, b, p_in_mesh, decide_at, slack, true);
    ASSERT_LE(d.lower_bound, truth + 1e-12) << i;
    ASSERT_GE(d.distance, truth - 1e-12) << i;
    if (d.lower_bound > decide_at) {
      ++far;
    } else {
      ++near;
      ASSERT_LE(truth, decide_at + slack + 1e-12) << i;  // not stopped while far above it
      ASSERT_LE(d.distance - d.lower_bound, slack + 1e-12) << i;
    }
    one_search += static_cast<long>(d.support_queries);
    const ConvexDistance first = convex_distance(a, b, p_in_mesh, decide_at);
    two_searches += static_cast<long>(first.support_queries);
    if (first.lower_bound <= decide_at) {
      two_searches += static_cast<long>(convex_distance(a, b, p_in_mesh, std::numeric_limits<double>::quiet_NaN(), slack).support_queries);
    }
  }
  std::cout << near << " near, " << far << " far; support queries " << one_search << " in one search, " << two_searches
            << " in two\n";
  EXPECT_GT(near, test::sized(200) / 8);
  EXPECT_GT(far, test::sized(200) / 8);
  EXPECT_LT(one_search, two_searches);
}

}  // namespace
}  // namespace bvh_collision
