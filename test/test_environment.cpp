// The robot against its environment: exact cube-triangle primitives against CGAL, a mesh against
// the octree against the same octree exploded into boxes (each checked with the pairwise BVH
// queries), solids, collision objects, and a whole robot (a mesh against a primitive:
// test_environment_mesh_primitive.cpp, one binary).
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

std::mt19937_64& rng() {
  static std::mt19937_64 r(42);
  return r;
}

TEST(CubeTriangle, AgainstCgal) {
  const Vec3 lo(0.25, -0.5, 1.0), hi(0.5, -0.25, 1.25);
  std::uniform_real_distribution<double> u(-0.35, 0.35), grid(-1, 5);
  int meets = 0, apart = 0;
  for (int i = 0; i < test::sized(4000); ++i) {
    Triangle t;
    for (int k = 0; k < 3; ++k) {
      // Vertices often exactly on the box's planes and edges (multiples of the side), where
      // rounding would decide a filtered test.
      const Vec3 snapped = lo + 0.0625 * Vec3(std::floor(grid(rng())), std::floor(grid(rng())), std::floor(grid(rng())));
      t[k] = i % 3 == 0 ? snapped : Vec3(0.375 + u(rng()), -0.375 + u(rng()), 1.125 + u(rng()));
    }
    if (i % 17 == 0) t[2] = t[1];                      // a segment
    if (i % 29 == 0) t[1] = t[2] = t[0];               // a point
    if (i % 13 == 0) t[2] = 0.5 * (t[0] + t[1]);       // collinear
    const bool expected = test::cgal_triangle_meets_box(t, lo, hi);
    ASSERT_EQ(triangle_meets_box(t, lo, hi), expected) << i;
    Vec3 on_t, on_b;
    const double d = triangle_box_distance(t, lo, hi, on_t, on_b);
    const double oracle = test::cgal_triangle_box_distance(t, lo, hi);
    ASSERT_NEAR(d, oracle, 1e-12) << i;
    EXPECT_NEAR((on_t - on_b).norm(), d, 1e-12);
    EXPECT_TRUE(((on_b.array() >= lo.array() - 1e-12) && (on_b.array() <= hi.array() + 1e-12)).all());
    meets += expected;
    apart += !expected;
  }
  // Both kinds well represented (about a quarter and a half of the cases).
  EXPECT_GT(meets, test::sized(4000) / 8);
  EXPECT_GT(apart, test::sized(4000) / 20);
}

// An octree with scattered voxels, a pruned block and free space.
Octree scene_tree(double resolution) {
  Octree tree(resolution);
  std::uniform_real_distribution<float> u(-0.4f, 0.4f);
  std::vector<ScanPoint> points;
  for (int i = 0; i < 300; ++i) points.emplace_back(u(rng()), u(rng()), u(rng()));
  insert_scan(tree, points, ScanPoint(0, 0, 1.5f));
  std::vector<ScanPoint> block;
  for (float x = 0.2f; x < 0.39f; x += 0.01f)
    for (float y = 0.2f; y < 0.39f; y += 0.01f)
      for (float z = -0.4f; z < -0.21f; z += 0.01f) block.emplace_back(x, y, z);
  for (int i = 0; i < 6; ++i) insert_points(tree, block);
  return tree;
}

struct Exploded {
  std::vector<Bvh<Obb>> boxes;
  std::vector<Transform> poses;
};

Exploded explode(const Octree& tree) {
  Exploded e;
  for (const auto& leaf : tree.leaves()) {
    if (!tree.occupied(leaf.log_odds)) continue;
    const double side = tree.cube_size(leaf.depth);
    e.boxes.push_back(Bvh<Obb>::build(box_mesh(Vec3::Constant(side))));
    e.poses.push_back(Transform::Translation(tree.cube_min(leaf.key) + Vec3::Constant(0.5 * side)));
  }
  return e;
}

void expect_mesh_matches_exploded(const TriangleMesh& mesh, const Octree& tree, double padding, int all_poses) {
  const int poses = test::sized(all_poses);
  const Bvh<Obb> bvh = Bvh<Obb>::build(mesh, BuildOptions{BuildMethod::kSah, 2});
  const Exploded boxes = explode(tree);
  std::uniform_real_distribution<double> u(-0.7, 0.7);
  int hits = 0, misses = 0;
  for (int i = 0; i < poses; ++i) {
    const Transform pose = test::random_rotation(rng(), Vec3(u(rng()), u(rng()), u(rng())));
    bool expected = false;
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t b = 0; b < boxes.boxes.size(); ++b) {
      CollisionRequest r;
      r.padding = padding;
      expected = expected || collide(bvh, pose, boxes.boxes[b], boxes.poses[b], r).collision;
      nearest = std::min(nearest, distance(bvh, pose, boxes.boxes[b], boxes.poses[b]).distance);
    }
    OctreeContact contact;
    const bool hit = mesh_meets_octree(bvh, pose, tree, padding, 0.0, true, &contact);
    ASSERT_EQ(hit, expected) << "pose " << i;
    const OctreeDistance d = mesh_octree_distance(bvh, pose, tree, true);
    ASSERT_NEAR(d.distance, nearest, 1e-9) << "pose " << i;
    if (d.distance > 0) {
      EXPECT_NEAR((d.on_link - d.on_cube).norm(), d.distance, 1e-9);
    }
    EXPECT_TRUE(tree.occupied(d.voxel.log_odds));
    // A tolerance may only add collisions, and only within padding + tolerance.
    const bool loose = mesh_meets_octree(bvh, pose, tree, padding, 0.03, true);
    EXPECT_TRUE(!expected || loose);
    if (loose) {
      EXPECT_LE(nearest, padding + 0.03 + 1e-12);
    }
    hits += expected;
    misses += !expected;
  }
  EXPECT_GT(hits, poses / 10);
  EXPECT_GT(misses, poses / 10);
}

TEST(MeshAgainstOctree, ClosedMeshAgainstExplodedBoxes) {
  const Octree tree = scene_tree(0.05);
  expect_mesh_matches_exploded(test::bumpy_sphere(rng(), 0.12, 8, 12, 0.2), tree, 0.0, 60);
  expect_mesh_matches_exploded(test::bumpy_sphere(rng(), 0.12, 8, 12, 0.2), tree, 0.02, 40);
}

TEST(MeshAgainstOctree, TriangleSoupAgainstExplodedBoxes) {
  const Octree tree = scene_tree(0.04);
  expect_mesh_matches_exploded(test::triangle_soup(rng(), 60, 0.3, 0.05), tree, 0.0, 60);
}

TEST(MeshAgainstOctree, RobotMeshAgainstExplodedBoxes) {
  BVH_REQUIRE_ROBOTS();
  const Octree tree = scene_tree(0.05);
  expect_mesh_matches_exploded(test::robot_mesh("panda/moveit_resources_panda_description/meshes/collision/hand.stl"),
                               tree, 0.0, 40);
}

// Solids: a link wholly inside a block of occupied voxels, and a voxel wholly inside a link.
TEST(MeshAgainstOctree, SolidsInsideEachOther) {
  Octree tree(0.02);
  std::vector<ScanPoint> block;
  for (float x = -0.3f; x < 0.3f; x += 0.01f)
    for (float y = -0.3f; y < 0.3f; y += 0.01f)
      for (float z = -0.3f; z < 0.3f; z += 0.01f) block.emplace_back(x, y, z);
  for (int i = 0; i < 3; ++i) insert_points(tree, block);
  const Bvh<Obb> small = Bvh<Obb>::build(test::bumpy_sphere(rng(), 0.05, 8, 12, 0.1));
  const Transform pose = Transform::Translation(Vec3(0.01, -0.02, 0.03));
  EXPECT_TRUE(mesh_meets_octree(small, pose, tree, 0.0, 0.0, true));
  EXPECT_EQ(mesh_octree_distance(small, pose, tree, true).distance, 0.0);

  Octree one(0.02);
  one.update(*one.grid().key(Vec3(0.01, 0.01, 0.01)), true);
  const Bvh<Obb> big = Bvh<Obb>::build(test::bumpy_sphere(rng(), 0.3, 10, 16, 0.1));
  ASSERT_TRUE(big.closed());
  EXPECT_TRUE(mesh_meets_octree(big, Transform::Identity(), one, 0.0, 0.0, true));
  EXPECT_FALSE(mesh_meets_octree(big, Transform::Identity(), one, 0.0, 0.0, false));
  EXPECT_EQ(mesh_octree_distance(big, Transform::Identity(), one, true).distance, 0.0);
  EXPECT_GT(mesh_octree_distance(big, Transform::Identity(), one, false).distance, 0.2);
}

// The tolerance's early exit may answer "collision" for a volume near a cube, but never beyond
// padding + tolerance (docs/design.md). Boxes (few triangles, flat leaf volumes) turned so
// that an edge faces a voxel's edge are separated only along the cross product of the two edges:
// a test of the boxes' face axes alone sees them overlap however far apart they are.
TEST(MeshAgainstOctree, ToleranceNeverReportsBeyondPaddingPlusTolerance) {
  const double res = 0.1;
  Octree tree(res);
  const Vec3 voxel(0.05, 0.05, 0.05);
  tree.update(*tree.grid().key(voxel), true);
  const Vec3 lo = tree.cube_min(*tree.grid().key(voxel)), hi = lo + Vec3::Constant(res);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int early = 0, checked = 0;
  for (int i = 0; i < test::sized(4000); ++i) {
    const TriangleMesh mesh = box_mesh(Vec3(0.02 + 0.2 * std::abs(u(rng())), 0.02 + 0.2 * std::abs(u(rng())), 0.3));
    const Bvh<Obb> bvh = Bvh<Obb>::build(mesh, BuildOptions{BuildMethod::kSah, 2});
    // Turned about a random axis near a diagonal, centred on the voxel's diagonal outside it.
    Transform pose = test::random_rotation(rng(), voxel + Vec3(1, 1, 0).normalized() * (0.1 + 0.25 * std::abs(u(rng()))) +
                                                      Vec3(u(rng()), u(rng()), u(rng())) * 0.05);
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      const Triangle tri = mesh.triangle(t);
      Vec3 on_t, on_b;
      d = std::min(d, triangle_box_distance(Triangle{{pose * tri[0], pose * tri[1], pose * tri[2]}}, lo, hi, on_t, on_b));
    }
    for (const double padding : {0.0, 0.005}) {
      for (const double tolerance : {0.002, 0.02}) {
        const bool hit = mesh_meets_octree(bvh, pose, tree, padding, tolerance, false);
        ++checked;
        if (hit && d > padding) ++early;
        ASSERT_FALSE(hit && d > padding + tolerance + 1e-12)
            << "case " << i << ": collision reported at distance " << d << " > padding " << padding << " + tolerance "
            << tolerance;
        if (d <= padding) {
          ASSERT_TRUE(hit) << "case " << i << ": a miss";
        }
      }
    }
  }
  std::cout << early << " of " << checked << " answers used the tolerance\n";
}

// A box meeting one voxel by a face, an edge or a corner, from each of the 26 directions, exactly
// touching, just apart and just overlapping, on both sides of the key origin and far from it.
// With dyadic sizes every coordinate is exact, so the oracle is the closed-interval overlap of the
// two boxes per axis; the cheap key-range and start-cube filters must not drop a touching voxel.
TEST(MeshAgainstOctree, BoxTouchingAVoxelFromEveryDirection) {
  const double res = 0.25, half = 0.375;  // the link box is 0.75 m wide, three voxels
  const Bvh<Obb> box = Bvh<Obb>::build(box_mesh(Vec3::Constant(2 * half)));
  int touching = 0;
  for (const Vec3& voxel : {Vec3(0.125, 0.125, 0.125), Vec3(-0.125, -0.125, 0.125), Vec3(100.125, -50.375, 7.625)}) {
    Octree tree(res);
    tree.update(*tree.grid().key(voxel), true);
    const Vec3 lo = tree.cube_min(*tree.grid().key(voxel)), hi = lo + Vec3::Constant(res);
    for (int dir = 0; dir < 27; ++dir) {
      const Vec3 d(dir % 3 - 1, dir / 3 % 3 - 1, dir / 9 - 1);
      if (d.isZero()) continue;
      for (const double gap : {0.0, 1.0 / 1024, -1.0 / 1024}) {
        const Vec3 centre = voxel + d * (0.5 * res + half + gap);
        const Vec3 box_lo = centre - Vec3::Constant(half), box_hi = centre + Vec3::Constant(half);
        const bool expected = (box_lo.array() <= hi.array()).all() && (lo.array() <= box_hi.array()).all();
        const Transform pose = Transform::Translation(centre);
        EXPECT_EQ(mesh_meets_octree(box, pose, tree, 0.0, 0.0, false), expected) << voxel.transpose() << " / " << d.transpose() << " gap " << gap;
        EXPECT_EQ(mesh_meets_octree(box, pose, tree, 0.0, 0.0, true), expected) << voxel.transpose() << " / " << d.transpose() << " gap " << gap;
        EXPECT_EQ(mesh_octree_distance(box, pose, tree, true).distance == 0.0, expected);
        touching += gap == 0.0 && expected;
      }
    }
  }
  EXPECT_EQ(touching, 3 * 26);  // touching counts as contact (closed sets)
}

TEST(PointAgainstOctree, NearestOccupiedCube) {
  const Octree tree = scene_tree(0.05);
  std::vector<Octree::Leaf> occupied;
  for (const auto& l : tree.leaves()) {
    if (tree.occupied(l.log_odds)) occupied.push_back(l);
  }
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const Vec3 p(u(rng()), u(rng()), u(rng()));
    double best = std::numeric_limits<double>::infinity();
    for (const auto& l : occupied) {
      const Vec3 lo = tree.cube_min(l.key), hi = lo + Vec3::Constant(tree.cube_size(l.depth));
      best = std::min(best, (p - p.cwiseMax(lo).cwiseMin(hi)).norm());
    }
    const OctreeDistance d = point_octree_distance(p, tree);
    ASSERT_EQ(d.distance, best);
    EXPECT_NEAR((d.on_cube - p).norm(), best, 1e-15);
    EXPECT_FALSE(std::isfinite(point_octree_distance(p, tree, best * 0.5).distance) && best > 0);
  }
}

TEST(Environment, ObjectsAddMoveRemoveAndBadInput) {
  Environment env(0.05);
  env.add_object("table", ObjectShape::box(Vec3(1.0, 0.8, 0.05)), Transform::Translation(Vec3(0.5, 0, 0.4)));
  env.add_object("ball", ObjectShape::sphere(0.05), Transform::Translation(Vec3(0.5, 0.2, 0.5)));
  env.add_object("can", ObjectShape::cylinder(0.04, 0.12), Transform::Translation(Vec3(0.4, -0.2, 0.5)));
  env.add_object("blob", ObjectShape::triangles(test::bumpy_sphere(rng(), 0.05, 6, 8, 0.1)), Transform::Identity());
  EXPECT_EQ(env.objects().size(), 4u);
  // Cylinders stay exact primitives (no prism); boxes are exact as triangles.
  EXPECT_EQ(env.find_object("can")->mesh, nullptr);
  EXPECT_EQ(env.find_object("can")->primitive.kind, Primitive::Kind::kCylinder);
  EXPECT_TRUE(env.find_object("table")->mesh->closed());
  EXPECT_TRUE(env.move_object("ball", Transform::Translation(Vec3(0, 0, 2))));
  EXPECT_EQ(env.find_object("ball")->pose.t.z(), 2.0);
  EXPECT_FALSE(env.move_object("nothing", Transform::Identity()));
  EXPECT_TRUE(env.remove_object("blob"));
  EXPECT_FALSE(env.remove_object("blob"));
  env.add_object("ball", ObjectShape::sphere(0.1), Transform::Identity());  // replaces
  EXPECT_EQ(env.objects().size(), 3u);
  EXPECT_EQ(env.find_object("ball")->shape.radius, 0.1);
  EXPECT_THROW(env.add_object("", ObjectShape::sphere(1), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::box(Vec3(1, 0, 1)), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::sphere(std::nan("")), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::cylinder(-1, 1), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::triangles(TriangleMesh{}), Transform::Identity()), std::invalid_argument);
  // Regression (make fuzz): sizes and places beyond 1e6 m, which overran the convex hull's memory
  // (a box 1e150 m wide) and the object grid's cell counts, are refused.
  EXPECT_THROW(env.add_object("bad", ObjectShape::box(Vec3::Constant(1e150)), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::sphere(2e6), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::capsule(1, 1e300), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(env.add_object("bad", ObjectShape::sphere(1), Transform::Translation(Vec3(0, -1e150, 0))), std::invalid_argument);
  EXPECT_THROW(env.move_object("ball", Transform::Translation(Vec3(2e6, 0, 0))), std::invalid_argument);
  TriangleMesh far;
  far.vertices = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1e7, 0)};
  far.triangles = {{0, 1, 2}};
  EXPECT_THROW(env.add_object("bad", ObjectShape::triangles(far), Transform::Identity()), std::invalid_argument);
  env.add_object("large", ObjectShape::box(Vec3::Constant(1e6)), Transform::Translation(Vec3(-1e6, 0, 0)));  // the limit itself
  EXPECT_TRUE(env.remove_object("large"));
  Transform skewed;
  skewed.R(0, 0) = 2.0;
  EXPECT_THROW(env.add_object("bad", ObjectShape::sphere(1), skewed), std::invalid_argument);
  EXPECT_THROW(env.move_object("ball", skewed), std::invalid_argument);
  EXPECT_EQ(env.objects().size(), 3u);
  EXPECT_EQ(env.find_object("bad"), nullptr);
  EXPECT_THROW(Environment(0.0), std::invalid_argument);
}

// A whole robot against an octree and objects, link by link against the exploded oracle.
// An object built outside the environment (the node builds it before taking the store's write
// lock) is the object add_object builds: same bounds, same hierarchy, replaces by id, and a bad
// one throws before the environment is touched.
TEST(Environment, ObjectsBuiltAheadEqualObjectsBuiltInPlace) {
  const ObjectShape blob = ObjectShape::triangles(test::bumpy_sphere(rng(), 0.05, 6, 8, 0.1));
  const Transform pose = Transform::Translation(Vec3(0.3, 0.1, 0.5));
  Environment in_place(0.05), ahead(0.05);
  in_place.add_object("blob", blob, pose);
  ahead.add_object(make_collision_object("blob", blob, pose));
  const CollisionObject& a = *in_place.find_object("blob");
  const CollisionObject& b = *ahead.find_object("blob");
  EXPECT_EQ(a.bound_center, b.bound_center);
  EXPECT_EQ(a.bound_radius, b.bound_radius);
  ASSERT_TRUE(a.mesh && b.mesh);
  EXPECT_EQ(a.mesh->nodes().size(), b.mesh->nodes().size());
  EXPECT_EQ(a.hull->vertices.size(), b.hull->vertices.size());
  ahead.add_object(make_collision_object("blob", ObjectShape::sphere(0.2), pose));  // replaces
  EXPECT_EQ(ahead.objects().size(), 1u);
  EXPECT_EQ(ahead.find_object("blob")->mesh, nullptr);
  EXPECT_THROW(make_collision_object("", blob, pose), std::invalid_argument);
  EXPECT_THROW(make_collision_object("bad", ObjectShape::sphere(-1.0), pose), std::invalid_argument);
}

TEST(RobotAgainstEnvironment, PandaAgainstExplodedScene) {
  BVH_REQUIRE_ROBOTS();
  const std::string dir = test::robots_dir() + "/panda";
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
  CheckerOptions options;
  options.link_padding["panda_hand"] = 0.01;
  const CollisionChecker checker(model, AllowedCollisionMatrix::adjacent_links(model), options);
  Environment env(0.04);
  // A table top of voxels in front of the robot, and objects.
  std::vector<ScanPoint> table;
  for (float x = 0.2f; x < 0.8f; x += 0.01f)
    for (float y = -0.4f; y < 0.4f; y += 0.01f) table.emplace_back(x, y, 0.3f);
  insert_scan(env.octree(), table, ScanPoint(0.5f, 0.0f, 1.5f));
  env.add_object("post", ObjectShape::cylinder(0.05, 1.0), Transform::Translation(Vec3(0.0, 0.5, 0.5)));
  env.add_object("ball", ObjectShape::sphere(0.1), Transform::Translation(Vec3(0.5, -0.3, 0.6)));
  const Exploded boxes = explode(env.octree());
  // The post is an exact cylinder: prisms inside it and around it (1e-6 m apart) bound it, and a
  // link that meets the inner one or misses the outer one has a known answer.
  TriangleMesh outer_mesh = cylinder_mesh(0.05, 1.0, 1e-6), inner_mesh = outer_mesh;
  for (Vec3& v : inner_mesh.vertices) {
    const double r = std::hypot(v.x(), v.y());
    if (r > 0) v.head<2>() *= 0.05 / r;  // the polygon's corners on the circle: inscribed
  }
  const Bvh<Obb> post_outer = Bvh<Obb>::build(outer_mesh), post_inner = Bvh<Obb>::build(inner_mesh);
  // Each link element's hierarchy, built once by the test (not taken from the checker it judges).
  std::vector<std::vector<Bvh<Obb>>> link_trees(checker.model().links().size());
  for (std::size_t l = 0; l < link_trees.size(); ++l) {
    for (const CollisionElement& e : checker.model().links()[l].collision) {
      ASSERT_NE(e.shape, CollisionElement::Shape::kSphere);  // panda: meshes only
      link_trees[l].push_back(Bvh<Obb>::build(*e.mesh));
    }
  }
  int colliding = 0, free = 0, undecided = 0;
  for (int i = 0; i < 60; ++i) {
    const std::vector<double> state = random_configuration(checker.model(), rng());
    std::vector<Transform> poses;
    forward_kinematics(checker.model(), state.data(), poses);
    std::set<int> expected;
    for (std::size_t l = 0; l < poses.size(); ++l) {
      const double padding = checker.link_padding(static_cast<int>(l));
      for (std::size_t k = 0; k < link_trees[l].size(); ++k) {
        const CollisionElement& e = checker.model().links()[l].collision[k];
        const Bvh<Obb>& link = link_trees[l][k];
        const Transform pose = poses[l] * e.origin;
        CollisionRequest r;
        r.padding = padding;
        const Transform post_pose = env.find_object("post")->pose;
        bool hit = collide(link, pose, post_inner, post_pose, r).collision;
        if (!hit && collide(link, pose, post_outer, post_pose, r).collision) ++undecided;
        hit = hit || point_distance(link, pose, Vec3(0.5, -0.3, 0.6)).distance <= 0.1 + padding ||
              contains_point(link, pose.inverse() * Vec3(0.5, -0.3, 0.6));
        for (std::size_t b = 0; b < boxes.boxes.size() && !hit; ++b) {
          hit = collide(link, pose, boxes.boxes[b], boxes.poses[b], r).collision;
        }
        if (hit) expected.insert(static_cast<int>(l));
      }
    }
    EnvironmentRequest request;
    request.all_links = true;
    const EnvironmentResult result = checker.check_environment(state.data(), env, request);
    std::set<int> got;
    for (const auto& c : result.contacts) got.insert(c.link);
    ASSERT_EQ(got, expected) << "state " << i;
    EXPECT_EQ(checker.check_environment(state.data(), env).collision, !expected.empty());
    colliding += !expected.empty();
    free += expected.empty();
  }
  EXPECT_GT(colliding, 5);
  EXPECT_GT(free, 5);
  EXPECT_EQ(undecided, 0) << "a link passed within 1e-6 m of the post's surface: the prisms cannot tell";
}

// Capsule objects are exact primitives (the points within `radius` of a segment): panda against a
// capsule, by distance and by boolean, against brute force over every link triangle and the
// segment (a degenerate triangle), minus the radius.
TEST(Environment, CapsuleObjectsAreExact) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const RobotModel& m = checker.model();
  const double radius = 0.04, length = 0.3;
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  int colliding = 0, free = 0;
  for (int i = 0; i < test::sized(40); ++i) {
    const std::vector<double> state = random_configuration(m, rng());
    const Transform pose = test::random_rotation(rng(), Vec3(0.3 + u(rng()), u(rng()), 0.5 + u(rng())));
    Environment env(0.05);
    env.add_object("capsule", ObjectShape::capsule(radius, length), pose);
    ASSERT_EQ(env.find_object("capsule")->mesh, nullptr);
    ASSERT_EQ(env.find_object("capsule")->primitive.kind, Primitive::Kind::kCapsule);
    const Vec3 p1 = pose * Vec3(0, 0, -0.5 * length), p2 = pose * Vec3(0, 0, 0.5 * length);
    std::vector<Transform> poses;
    forward_kinematics(m, state.data(), poses);
    double truth = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < m.links().size(); ++l) {
      for (const CollisionElement& e : m.links()[l].collision) {
        ASSERT_TRUE(e.mesh) << "panda's links are meshes";
        const Transform to_world = poses[l] * e.origin;
        for (std::size_t t = 0; t < e.mesh->triangles.size(); ++t) {
          const Triangle tri = e.mesh->triangle(t);
          const Triangle world{{to_world * tri[0], to_world * tri[1], to_world * tri[2]}};
          truth = std::min(truth, triangle_triangle_distance(world, Triangle{{p1, p2, p2}}).distance - radius);
        }
      }
    }
    EnvironmentRequest request;
    request.distance = true;
    request.all_links = true;
    request.solids = false;  // the oracle sees surfaces
    const EnvironmentResult r = checker.check_environment(state.data(), env, request);
    if (truth > 1e-9) {
      ++free;
      EXPECT_FALSE(r.collision) << i;
      EXPECT_NEAR(r.min_distance, truth, 1e-9) << i;
    } else if (truth < -1e-9) {
      ++colliding;
      EXPECT_TRUE(r.collision) << i;
      EXPECT_EQ(r.min_distance, 0.0) << i;
    }
  }
  EXPECT_GT(free, 0);
  EXPECT_GT(colliding, 0);
  EXPECT_THROW(Environment(0.05).add_object("c", ObjectShape::capsule(0.0, 1.0), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(Environment(0.05).add_object("c", ObjectShape::capsule(0.1, -1.0), Transform::Identity()), std::invalid_argument);
}

// A cone object (shape_msgs' CONE) stays an exact cone: panda's link meshes against it agree
// with FCL's cone (its GJK with a 1e-12 tolerance; decisions are compared where its answer is
// clear of 1e-5 m, distances from above exactly and from below within 1e-6 m); a cone without
// volume is refused.
TEST(Environment, ConeObjectsAreExact) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const RobotModel& m = checker.model();
  const double radius = 0.08, length = 0.3;
  auto fcl_cone = std::make_shared<fcl::Coned>(radius, length);
  std::map<const TriangleMesh*, std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>> fcl_links;
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  int colliding = 0, free = 0;
  for (int i = 0; i < test::sized(40); ++i) {
    const std::vector<double> state = random_configuration(m, rng());
    const Transform pose = test::random_rotation(rng(), Vec3(0.3 + u(rng()), u(rng()), 0.5 + u(rng())));
    Environment env(0.05);
    env.add_object("cone", ObjectShape::cone(radius, length), pose);
    ASSERT_EQ(env.find_object("cone")->mesh, nullptr);
    ASSERT_EQ(env.find_object("cone")->primitive.kind, Primitive::Kind::kCone);
    std::vector<Transform> poses;
    forward_kinematics(m, state.data(), poses);
    double truth = std::numeric_limits<double>::infinity();
    fcl::CollisionObjectd cone_object(fcl_cone, test::fcl_transform(pose));
    for (std::size_t l = 0; l < m.links().size(); ++l) {
      for (const CollisionElement& e : m.links()[l].collision) {
        ASSERT_TRUE(e.mesh) << "panda's links are meshes";
        auto& model = fcl_links[e.mesh.get()];
        if (!model) model = test::fcl_model<fcl::OBBRSSd>(*e.mesh);
        fcl::CollisionObjectd link_object(model, test::fcl_transform(poses[l] * e.origin));
        fcl::DistanceRequestd request;
        request.enable_signed_distance = false;
        request.gjk_solver_type = fcl::GST_INDEP;  // libccd's default stops about 1e-5 m short
        request.distance_tolerance = 1e-12;
        fcl::DistanceResultd result;
        fcl::distance(&link_object, &cone_object, request, result);
        fcl::CollisionRequestd touch;
        fcl::CollisionResultd touching;
        fcl::collide(&link_object, &cone_object, touch, touching);
        truth = std::min(truth, touching.isCollision() ? -1.0 : result.min_distance);
      }
    }
    EnvironmentRequest request;
    request.distance = true;
    request.all_links = true;
    request.solids = false;  // FCL's meshes are surfaces
    const EnvironmentResult r = checker.check_environment(state.data(), env, request);
    if (truth > 1e-5) {
      ++free;
      EXPECT_FALSE(r.collision) << i;
      // FCL's GJK stops at points of the two sets: the true distance is at most its answer, and
      // ours (exact up to rounding) may not exceed it; nor lie below it by more than FCL's error.
      EXPECT_LE(r.min_distance, truth + 1e-9) << i;
      EXPECT_GE(r.min_distance, truth - 1e-6) << i;
    } else if (truth < 0.0) {
      ++colliding;
      EXPECT_TRUE(r.collision) << i;
      EXPECT_EQ(r.min_distance, 0.0) << i;
    }
  }
  EXPECT_GT(free, 0);
  EXPECT_GT(colliding, 0);
  EXPECT_THROW(Environment(0.05).add_object("c", ObjectShape::cone(0.0, 1.0), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(Environment(0.05).add_object("c", ObjectShape::cone(0.1, 0.0), Transform::Identity()), std::invalid_argument);
  EXPECT_THROW(Environment(0.05).add_object("c", ObjectShape::cone(0.1, NAN), Transform::Identity()), std::invalid_argument);
}

}  // namespace
}  // namespace bvh_collision
