// Limits (geometry/limits.h, issue 19): every limit of the library refuses at once, names itself
// and the node parameter that raises it, and changes nothing; at the limit the work is done.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <random>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"

namespace bvh_collision {
namespace {

CollisionChecker demo(const Limits& limits = {}) {
  CheckerOptions options;
  options.limits = limits;
  return test::demo_arm_checker(options);
}

// The message names what, how much, the limit and the parameter.
template <class Call>
std::string refusal(Call&& call) {
  try {
    call();
  } catch (const LimitExceeded& e) {
    return e.what();
  }
  return "(no LimitExceeded)";
}

// 3 rad at 1e-9 rad once ran for ten minutes; 1e-300 made the number of states undefined. Both
// are refused at once; exactly the limit's states are checked.
TEST(Limits, FixedStepMotions) {
  Limits limits;
  limits.motion_states = 101;
  const CollisionChecker checker = demo(limits);
  const Environment env(0.02);
  std::vector<double> a(checker.model().variable_count(), 0.0), b = a;
  a[0] = -1.5, b[0] = 1.5;
  MotionRequest request;
  // The count is computed, not walked: the message names it (about 3e9 states at 1e-9 rad).
  for (const auto& [resolution, needs] : {std::pair<double, const char*>{1e-9, "needs 300000000"}, {1e-300, "needs 3e+300"},
                                          {0.0299, "needs 102"}}) {
    request.resolution = resolution;
    const std::string message = refusal([&] { checker.check_motion(a.data(), b.data(), env, request); });
    EXPECT_NE(message.find("~max_motion_states"), std::string::npos) << message;
    EXPECT_NE(message.find("limit of 101"), std::string::npos) << message;
    EXPECT_NE(message.find(needs), std::string::npos) << message;
  }
  request.resolution = 0.03;  // 100 steps: 101 states
  EXPECT_EQ(checker.check_motion(a.data(), b.data(), env, request).states_checked, 101u);
  // The default allows 100,000.
  const CollisionChecker defaults = demo();
  request.resolution = 1e-9;
  EXPECT_NE(refusal([&] { defaults.check_motion(a.data(), b.data(), env, request); }).find("100000"), std::string::npos);
}

TEST(Limits, Batches) {
  Limits limits;
  limits.batch_states = 10;
  const CollisionChecker checker = demo(limits);
  const std::vector<double> states(11 * checker.model().variable_count(), 0.0);
  BatchRequest request;
  request.environment = false;
  const std::string message = refusal([&] { checker.check_batch(states.data(), 11, nullptr, request); });
  EXPECT_NE(message.find("~max_batch_states"), std::string::npos) << message;
  EXPECT_NE(message.find("needs 11"), std::string::npos) << message;
  EXPECT_EQ(checker.check_batch(states.data(), 10, nullptr, request).size(), 10u);
}

// A robot beyond the limits is refused before any hierarchy is built.
TEST(Limits, RobotLinksAndCheckedPairs) {
  Limits links;
  links.robot_links = 5;
  EXPECT_NE(refusal([&] { demo(links); }).find("~max_robot_links"), std::string::npos);
  Limits pairs;
  pairs.checked_pairs = 3;
  EXPECT_NE(refusal([&] { demo(pairs); }).find("~max_checked_pairs"), std::string::npos);
  Limits exact;
  exact.robot_links = demo().model().links().size();
  exact.checked_pairs = demo().checked_pairs().size();
  EXPECT_NO_THROW(demo(exact));
}

// A robot with one 200,000-vertex closed mesh (a 400k-triangle binary STL) once kept a node from
// coming up for minutes (a quadratic hull) and then for 11 s (sampled slack and the box search
// on every node); it loads in about 2 s now (make bench: bench_stability's large_mesh table,
// against FCL's build of the same mesh). Here the work is bounded, not the time: the hull's
// point-against-face tests stay within a small multiple of n log n (a quadratic hull makes
// n^2 / 2, 2e10 here), and the slack of a mesh over 50k triangles is bounded from corners, a
// few distances a triangle (sampled on every node: 64 per triangle on every level, ~5e8).
TEST(Limits, LargeMeshLoadsWithBoundedWork) {
  std::mt19937_64 rng(5);
  const int rings = test::sized(400), segments = 500;
  const TriangleMesh ball = test::bumpy_sphere(rng, 0.1, rings, segments, 0.002);
  const std::string path = ::testing::TempDir() + "bvh_collision_large_mesh.stl";
  test::write_binary_stl(ball, path);
  const std::string urdf = R"(<robot name="large"><link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
    <link name="ball"><collision><geometry><mesh filename=")" + path + R"("/></geometry></collision></link>
    <joint name="j" type="revolute"><parent link="base"/><child link="ball"/><origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>)";
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(urdf), PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  const CollisionChecker checker(std::move(model), std::move(acm), {});
  std::remove(path.c_str());
  const auto& meshes = checker.collision_model().meshes();  // the base's box and the ball
  ASSERT_EQ(meshes.size(), 2u);
  const std::size_t l = meshes[0].triangles().size() > meshes[1].triangles().size() ? 0 : 1;
  const auto& large = meshes[l];
  EXPECT_TRUE(large.closed());
  EXPECT_EQ(large.triangles().size(), ball.triangles.size());
  const double n = static_cast<double>(ball.vertices.size()), triangles = static_cast<double>(ball.triangles.size());
  const std::uint64_t hull_tests = checker.collision_model().hulls()[l].orientation_tests;
  EXPECT_GT(hull_tests, 0u);
  EXPECT_LT(static_cast<double>(hull_tests), 64.0 * n * std::log2(n)) << "the hull's work is no longer n log n";
  EXPECT_GT(large.slack_evaluations(), 0u);
  if (triangles > 50000) {
    EXPECT_LT(static_cast<double>(large.slack_evaluations()), 16.0 * triangles) << "a large mesh took the sampled slack";
  }
  std::cout << ball.vertices.size() << " vertices, " << ball.triangles.size() << " triangles: " << hull_tests
            << " hull tests (n log2 n = " << n * std::log2(n) << "), " << large.slack_evaluations() << " slack distances\n";
  // It answers: a ray down onto the ball (radius 0.1, bumps under 2 mm, centre at 0.5 m) meets it.
  const double state[1] = {0.3};
  const RayCastResult hit = checker.cast_ray(state, Environment(0.05), Vec3(0.0, 0.0, 1.0), Vec3(0.0, 0.0, -1.0), 2.0);
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(checker.model().links()[hit.link].name, "ball");
  EXPECT_NEAR(hit.point.z(), 0.6, 0.005);
}

// A scan beyond the point limit, or with rays longer than the voxel limit, changes nothing.
TEST(Limits, Scans) {
  Octree tree(0.02);
  const std::vector<ScanPoint> points(1001, ScanPoint(1.0f, 0.0f, 0.0f));
  const std::uint64_t revision = tree.revision();
  ScanOptions options;
  options.limits.cloud_points = 1000;
  std::string message = refusal([&] { insert_scan(tree, points, ScanPoint::Zero(), options); });
  EXPECT_NE(message.find("~max_cloud_points"), std::string::npos) << message;
  options.limits.cloud_points = 2000;
  options.max_range = 100.0;  // 5,000 voxels a ray at 2 cm
  options.limits.ray_voxels = 4999;
  message = refusal([&] { insert_scan(tree, points, ScanPoint::Zero(), options); });
  EXPECT_NE(message.find("~max_ray_voxels"), std::string::npos) << message;
  EXPECT_EQ(tree.revision(), revision) << "a refused scan changed the octree";
  EXPECT_EQ(tree.node_count(), Octree(0.02).node_count());
  options.limits.ray_voxels = 5000;
  EXPECT_EQ(insert_scan(tree, points, ScanPoint::Zero(), options).points, 1001u);
}

TEST(Limits, MessagesSayHowMuch) {
  EXPECT_EQ(LimitExceeded("a batch", 12, 10, "max_batch_states").what(),
            std::string("a batch needs 12, more than the limit of 10 (parameter ~max_batch_states raises it)"));
  EXPECT_NE(std::string(LimitExceeded("x", INFINITY, 1, "p").what()).find("an unbounded number"), std::string::npos);
  EXPECT_THROW(check_limit("x", std::nan(""), 1, "p"), LimitExceeded);
  EXPECT_NO_THROW(check_limit("x", 1.0, 1, "p"));
}

}  // namespace
}  // namespace bvh_collision
