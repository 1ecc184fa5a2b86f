// The hard-case suite at mesh level, and FCL as a second oracle on real link meshes.
#include <gtest/gtest.h>

#include "fcl_oracle.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(11);
  return r;
}

// Box b sits beside box a along x with a face gap of `gap` (negative: overlap), both meshes in
// their own local coordinates; both poses are the same exactly representable pose, so the
// relative transform is exactly the identity wherever the scene is.
struct FacePair {
  TriangleMesh a, b;
};

FacePair boxes_with_gap(double size, double gap) {
  FacePair p{box_mesh(Vec3::Constant(size)), box_mesh(Vec3::Constant(size))};
  for (Vec3& v : p.b.vertices) v.x() += size + gap;
  return p;
}

template <class BV>
void check_face_gaps() {
  const Mat3 quarter_turn = (Mat3() << 0, -1, 0, 1, 0, 0, 0, 0, 1).finished();  // exact
  for (double size : {0.001, 0.01, 0.1, 1.0, 10.0, 100.0}) {
    for (double relative_gap : {1e-15, -1e-15}) {
      const FacePair boxes = boxes_with_gap(size, relative_gap * size);
      const auto a = Bvh<BV>::build(boxes.a), b = Bvh<BV>::build(boxes.b);
      for (double offset : {0.0, 1e3, 1e4}) {
        for (const Mat3& rotation : {Mat3(Mat3::Identity()), quarter_turn}) {
          const Transform pose{rotation, Vec3(offset, -offset, offset)};
          const bool expected = relative_gap < 0;
          SCOPED_TRACE(std::string(volume_name<BV>()) + " size " + std::to_string(size) + " gap " +
                       std::to_string(relative_gap) + " offset " + std::to_string(offset));
          EXPECT_EQ(collide(a, pose, b, pose).collision, expected);
          const double d = distance(a, pose, b, pose).distance;
          if (expected) {
            EXPECT_EQ(d, 0.0);
          } else {
            EXPECT_GT(d, 0.0);
            EXPECT_LT(d, 1e-14 * size);
          }
        }
      }
    }
  }
}

TEST(HardCases, BoxFaceGapsAtEveryScaleAndOffset) {
  check_face_gaps<Aabb>();
  check_face_gaps<Obb>();
  check_face_gaps<Sphere>();
  check_face_gaps<Kdop14>();
  check_face_gaps<Kdop18>();
  check_face_gaps<Kdop26>();
  check_face_gaps<Rss>();
}

TEST(HardCases, TouchingFacesCollide) {
  const FacePair boxes = boxes_with_gap(1.0, 0.0);
  const auto a = Bvh<Obb>::build(boxes.a), b = Bvh<Obb>::build(boxes.b);
  EXPECT_TRUE(collide(a, Transform(), b, Transform()).collision);
  EXPECT_EQ(distance(a, Transform(), b, Transform()).distance, 0.0);
}

TEST(HardCases, SmallClosedMeshWhollyInsideLargeOne) {
  const TriangleMesh big = test::bumpy_sphere(rng(), 1.0, 16, 24, 0.05);
  const TriangleMesh small = test::bumpy_sphere(rng(), 0.05, 6, 8, 0.1);
  const auto a = Bvh<Rss>::build(big), b = Bvh<Rss>::build(small);
  ASSERT_TRUE(a.closed() && b.closed());
  for (double offset : {0.0, 1e3, 1e4}) {
    const Transform pose = Transform::Translation(Vec3::Constant(offset));
    const Transform inside{Mat3::Identity(), Vec3(offset + 0.3, offset - 0.2, offset + 0.1)};
    EXPECT_TRUE(collide(a, pose, b, inside).collision);
    EXPECT_EQ(distance(a, pose, b, inside).distance, 0.0);
    const Transform outside{Mat3::Identity(), Vec3(offset + 1.5, offset, offset)};
    EXPECT_FALSE(collide(a, pose, b, outside).collision);
  }
}

TEST(HardCases, DegenerateTrianglesInMeshesStillCollide) {
  // A mesh made only of zero-area triangles (segments) piercing a box face.
  TriangleMesh needles;
  for (int i = 0; i < 10; ++i) {
    const double y = -0.4 + 0.08 * i;
    const auto base = static_cast<std::int32_t>(needles.vertices.size());
    needles.vertices.insert(needles.vertices.end(), {Vec3(0.3, y, 0), Vec3(0.6, y, 0), Vec3(0.9, y, 0)});
    needles.triangles.push_back({base, base + 1, base + 2});
  }
  const auto box = Bvh<Aabb>::build(box_mesh(Vec3(1, 1, 1)));
  const auto n = Bvh<Aabb>::build(needles);
  EXPECT_TRUE(collide(box, Transform(), n, Transform()).collision);  // they cross the x = 0.5 face
  EXPECT_FALSE(collide(box, Transform(), n, Transform::Translation(Vec3(0.21, 0, 0))).collision);
}

// FCL as a second oracle on real meshes (its own BVH and triangle routines).
TEST(FclOracle, DistanceAndCollisionAgreeOnRealMeshes) {
  BVH_REQUIRE_ROBOTS();
  const std::string ur5e = "ur5e/ur_description/meshes/ur5e/collision/";
  const std::string panda = "panda/moveit_resources_panda_description/meshes/collision/";
  const std::pair<std::string, std::string> pairs[] = {{panda + "link5.stl", panda + "link6.stl"},
                                                       {ur5e + "wrist1.stl", ur5e + "wrist3.stl"}};
  int compared = 0;
  for (const auto& [fa, fb] : pairs) {
    const TriangleMesh ma = test::robot_mesh(fa), mb = test::robot_mesh(fb);
    const auto a = Bvh<Rss>::build(ma), b = Bvh<Rss>::build(mb);
    const auto guide_a = Bvh<Aabb>::build(ma), guide_b = Bvh<Aabb>::build(mb);
    const auto fcl_a = test::fcl_model<fcl::RSSd>(ma), fcl_b = test::fcl_model<fcl::RSSd>(mb);
    const auto fcl_oa = test::fcl_model<fcl::OBBRSSd>(ma), fcl_ob = test::fcl_model<fcl::OBBRSSd>(mb);
    for (int p = 0; p < 150; ++p) {
      const Transform pose = test::near_contact_pose(rng(), guide_a, guide_b);
      CollisionRequest surfaces;
      surfaces.solids = false;  // FCL treats meshes as surfaces
      const double ours = distance(a, Transform(), b, pose).distance;
      const bool ours_hit = collide(a, Transform(), b, pose, surfaces).collision;
      if (ours > 0.0) {
        EXPECT_NEAR(test::fcl_distance(fcl_a, Transform(), fcl_b, pose), ours, 1e-9 + 1e-6 * ours) << fa << " pose " << p;
      }
      if (ours > 1e-9 || ours_hit) {  // FCL's collision is not exact at grazing contact
        EXPECT_EQ(test::fcl_collide(fcl_oa, Transform(), fcl_ob, pose), ours_hit) << fa << " pose " << p << " d " << ours;
      }
      ++compared;
    }
  }
  EXPECT_EQ(compared, 300);
}

}  // namespace
}  // namespace bvh_collision
