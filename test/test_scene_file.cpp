// MoveIt `.scene` files in and out (checker/scene_file.h): MoveIt's two formats read as MoveIt
// reads them, a round trip to the same doubles and the same text, the same answers as the same
// objects added one by one, and every malformed input refused by file, line and field.
#include <gtest/gtest.h>

#include <sstream>

#include "bvh_collision/checker/collision_checker.h"
#include "bvh_collision/checker/scene_file.h"
#include "checker_fixtures.h"
#include "planning_scenes.h"

namespace bvh_collision {
namespace {

Transform posed(double x, double y, double z, double angle, const Vec3& axis) {
  Transform t;
  t.R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  t.t = Vec3(x, y, z);
  return t;
}

TriangleMesh tetrahedron(double s) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

// Every kind a scene can hold, an object of several shapes and a posed object.
SceneFile every_kind() {
  SceneFile s;
  s.name = "every kind";
  s.objects.push_back({"table", posed(0.6, 0.1, 0.0, 0.3, Vec3::UnitZ()),
                       {{ObjectShape::box({0.5, 0.8, 0.03}), posed(0, 0, 0.4, 0, Vec3::UnitZ())},
                        {ObjectShape::cylinder(0.02, 0.4), posed(0.2, 0.35, 0.2, 0, Vec3::UnitZ())},
                        {ObjectShape::cone(0.05, 0.1), posed(-0.1, 0.0, 0.46, 0.7, Vec3(1, 1, 0))}}});
  s.objects.push_back({"ball", Transform(), {{ObjectShape::sphere(0.07), posed(0.3, -0.4, 0.6, 0, Vec3::UnitZ())}}});
  s.objects.push_back({"part with spaces", posed(0.4, 0.4, 0.7, 1.1, Vec3(0, 1, 1)),
                       {{ObjectShape::triangles(tetrahedron(0.1)), Transform()}}});
  return s;
}

std::string text_of(const SceneFile& s) {
  std::ostringstream out;
  write_scene_text(s, out);
  return out.str();
}

SceneFile read_text(const std::string& text) {
  std::istringstream in(text);
  return read_scene_text(in, "test.scene");
}

void expect_same_scene(const SceneFile& a, const SceneFile& b) {
  ASSERT_EQ(a.name, b.name);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    const SceneObject& x = a.objects[i];
    const SceneObject& y = b.objects[i];
    EXPECT_EQ(x.id, y.id);
    EXPECT_TRUE(x.pose.R.isApprox(y.pose.R, 1e-15) && x.pose.t == y.pose.t) << x.id;
    ASSERT_EQ(x.shapes.size(), y.shapes.size());
    for (std::size_t k = 0; k < x.shapes.size(); ++k) {
      const ObjectShape& p = x.shapes[k].shape;
      const ObjectShape& q = y.shapes[k].shape;
      EXPECT_EQ(p.kind, q.kind);
      EXPECT_EQ(p.size, q.size);
      EXPECT_EQ(p.radius, q.radius);
      EXPECT_EQ(p.length, q.length);
      EXPECT_EQ(p.triangle_count(), q.triangle_count());
      if (p.mesh) {
        EXPECT_EQ(p.mesh->vertices, q.mesh->vertices);
        EXPECT_EQ(p.mesh->triangles, q.mesh->triangles);
      }
      EXPECT_TRUE(x.shapes[k].pose.R.isApprox(y.shapes[k].pose.R, 1e-15) && x.shapes[k].pose.t == y.shapes[k].pose.t);
    }
  }
}

// Token by token: words equal, numbers within 1e-15.
void expect_same_text(const std::string& a, const std::string& b) {
  std::istringstream x(a), y(b);
  std::string p, q;
  while (x >> p) {
    ASSERT_TRUE(static_cast<bool>(y >> q)) << "the second text ends first";
    char* end = nullptr;
    const double u = std::strtod(p.c_str(), &end);
    if (*end != '\0' || p.empty()) {
      EXPECT_EQ(p, q);
      continue;
    }
    EXPECT_NEAR(u, std::strtod(q.c_str(), nullptr), 1e-15) << p << " / " << q;
  }
  EXPECT_FALSE(static_cast<bool>(y >> q)) << "the first text ends first";
}

TEST(SceneFile, RoundTripsToTheSameNumbersAndText) {
  const SceneFile original = every_kind();
  const std::string text = text_of(original);
  const SceneFile back = read_text(text);
  expect_same_scene(original, back);
  // Written again: the same text, but for the last digits of a quaternion (one carried through
  // a rotation matrix and back).
  expect_same_text(text_of(back), text);
  // The generated benchmark scenes too (boxes, cylinders, spheres; up to 60 shapes).
  for (int k = 0; k < 8; ++k) {
    const SceneFile scene = test::generate_scene(2026, k);
    expect_same_scene(scene, read_text(text_of(scene)));
  }
}

// What MoveIt writes: the newer format (object pose, colours, subframes) and the older one (no
// object pose, no subframes), as shapes::saveAsText lays out each shape (a cylinder's radius
// before its length).
TEST(SceneFile, ReadsBothOfMoveItsFormats) {
  const std::string newer =
      "(noname)+\n"
      "* box_with_handle\n"
      "1 0 0.5\n"
      "0 0 0.70710678118654757 0.70710678118654757\n"
      "2\n"
      "box\n"
      "0.2 0.1 0.3\n"
      "0 0 0\n"
      "0 0 0 1\n"
      "0.5 0.5 0.5 1\n"
      "cylinder\n"
      "0.02 0.15\n"
      "0 0.1 0\n"
      "0 0 0 1\n"
      "0 0 0 0\n"
      "1\n"
      "handle\n"
      "0 0.1 0\n"
      "0 0 0 1\n"
      ".\n";
  const SceneFile a = read_text(newer);
  EXPECT_EQ(a.name, "(noname)+");
  ASSERT_EQ(a.objects.size(), 1u);
  ASSERT_EQ(a.objects[0].shapes.size(), 2u);
  EXPECT_EQ(a.objects[0].shapes[1].shape.kind, ObjectShape::Kind::kCylinder);
  EXPECT_EQ(a.objects[0].shapes[1].shape.radius, 0.02);
  EXPECT_EQ(a.objects[0].shapes[1].shape.length, 0.15);
  // The cylinder at (0, 0.1, 0) in an object turned a quarter about z at (1, 0, 0.5): at (0.9, 0, 0.5).
  const std::vector<CollisionObject> objects = a.collision_objects();
  ASSERT_EQ(objects.size(), 2u);
  EXPECT_EQ(objects[0].id, "box_with_handle#0");
  EXPECT_EQ(objects[1].id, "box_with_handle#1");
  EXPECT_TRUE(objects[1].pose.t.isApprox(Vec3(0.9, 0.0, 0.5), 1e-12)) << objects[1].pose.t.transpose();

  const std::string older =
      "old scene\n"
      "* pole\n"
      "1\n"
      "cone\n"
      "0.1 0.4\n"
      "0.5 0 0.2\n"
      "0 0 0 1\n"
      "0 0 0 0\n"
      "* pole\n"  // the same id again: it replaces the first, as in MoveIt
      "1\n"
      "sphere\n"
      "0.05\n"
      "0.5 0 0.2\n"
      "0 0 0 1\n"
      "0 0 0 0\n"
      ".\n";
  const SceneFile b = read_text(older);
  ASSERT_EQ(b.objects.size(), 1u);
  EXPECT_EQ(b.objects[0].shapes[0].shape.kind, ObjectShape::Kind::kSphere);
  EXPECT_EQ(b.collision_objects()[0].id, "pole");
}

// A scene's environment answers as the same objects added one by one, each posed in the world.
TEST(SceneFile, ChecksAsTheSameObjectsAddedOneByOne) {
  const CollisionChecker checker = test::demo_arm_checker();
  const SceneFile scene = read_text(text_of(every_kind()));
  const Environment from_file = scene.environment();
  Environment by_hand(0.05);
  by_hand.add_object("table#0", ObjectShape::box({0.5, 0.8, 0.03}), every_kind().objects[0].pose * posed(0, 0, 0.4, 0, Vec3::UnitZ()));
  by_hand.add_object("table#1", ObjectShape::cylinder(0.02, 0.4), every_kind().objects[0].pose * posed(0.2, 0.35, 0.2, 0, Vec3::UnitZ()));
  by_hand.add_object("table#2", ObjectShape::cone(0.05, 0.1), every_kind().objects[0].pose * posed(-0.1, 0.0, 0.46, 0.7, Vec3(1, 1, 0)));
  by_hand.add_object("ball", ObjectShape::sphere(0.07), posed(0.3, -0.4, 0.6, 0, Vec3::UnitZ()));
  by_hand.add_object("part with spaces", ObjectShape::triangles(tetrahedron(0.1)), posed(0.4, 0.4, 0.7, 1.1, Vec3(0, 1, 1)));
  std::mt19937_64 rng(5);
  EnvironmentRequest request;
  request.distance = true;
  request.all_links = true;
  int colliding = 0;
  for (int i = 0; i < test::sized(400); ++i) {
    const std::vector<double> q = random_configuration(checker.model(), rng);
    const EnvironmentResult a = checker.check_environment(q.data(), from_file, request);
    const EnvironmentResult b = checker.check_environment(q.data(), by_hand, request);
    ASSERT_EQ(a.collision, b.collision) << i;
    ASSERT_EQ(a.contacts.size(), b.contacts.size()) << i;
    for (std::size_t c = 0; c < a.contacts.size(); ++c) EXPECT_EQ(a.contacts[c].object, b.contacts[c].object) << i;
    if (!a.collision) EXPECT_NEAR(a.min_distance, b.min_distance, 1e-12) << i;
    colliding += a.collision;
  }
  EXPECT_GT(colliding, 0) << "the scene never touched the arm: the comparison shows nothing";
}

// Each malformed input: refused naming the file, the line and the field.
TEST(SceneFile, RefusesMalformedInputByFileLineAndField) {
  const std::string head = "scene\n* thing\n0 0 0\n0 0 0 1\n1\n";  // newer format, one shape
  const std::string tail = "0 0 0\n0 0 0 1\n0 0 0 0\n0\n.\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"", "test.scene:1: empty"},
      {"scene\n", "test.scene:1: an object ('*') or the end ('.'): missing"},
      {"scene\n* thing\n0 0 0\n0 0 0 1\n1\nbox\n0.1 0.2 0.3\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n", "missing (the file ends first)"},
      {head + "box\n0.1 -0.2 0.3\n" + tail, "test.scene:7: object 'thing' shape 1 (box) size 2 is not a positive number"},
      {head + "box\n0.1 0.2\n" + tail, "test.scene:8: object 'thing' shape 1 (box) size 3 is not a positive number"},
      {head + "box\n0.1 nan 0.3\n" + tail, "test.scene:7: object 'thing' shape 1 (box) size 2: 'nan' is not a number"},
      {head + "box\n0.1 0x10 0.3\n" + tail, "'0x10' is not a number"},
      {head + "box\n0.1 1e999 0.3\n" + tail, "'1e999' is not finite"},
      {head + "box\n1e6 1 1\n" + tail, "size 1 is not a positive number up to 1e5 m"},
      {head + "plane\n0 0 1 0\n" + tail, "test.scene:6: object 'thing' shape 1: a plane (infinite) is not supported"},
      {head + "torus\n1 2\n" + tail, "test.scene:6: object 'thing' shape 1: unknown shape type 'torus'"},
      {head + "sphere\n0.1\n0 0 0\n0 0 0 2\n0 0 0 0\n0\n.\n", "test.scene:9: object 'thing' shape 1 pose: orientation is not a unit quaternion (norm 2)"},
      {head + "mesh\n3 1\n0 0 0\n1 0 0\n0 1 0\n0 1 3\n" + tail, "object 'thing' shape 1 (mesh) triangle 0: vertex 3 of 3"},
      {head + "mesh\n3 0\n0 0 0\n1 0 0\n0 1 0\n" + tail, "(mesh): no triangle"},
      {head + "mesh\n3 -1\n" + tail, "(mesh) triangle count: '-1' is not a whole number"},
      {"scene\n* thing\n0 0 0\n0 0 0 1\n0\n0\n.\n", "test.scene:5: object 'thing': no shape"},
      {"scene\n* a#1\n0 0 0\n0 0 0 1\n1\nsphere\n1\n" + tail, "test.scene:2: object id 'a#1' contains '#'"},
      {"scene\n*\n1\nsphere\n1\n0 0 0\n0 0 0 1\n0 0 0 0\n.\n", "test.scene:2: an object without an id"},
      {"scene\n+ thing\n.\n", "test.scene:2: '+' where an object"},
      {"scene\n* thing\n0 0 0\n0 0 0 1\n1\nsphere\n1\n0 0 0\n0 0 0 1\n0 0 zero 0\n0\n.\n", "test.scene:10: object 'thing' shape 1 colour b: 'zero' is not a number"},
  };
  for (const auto& [text, expected] : cases) {
    try {
      read_text(text);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const SceneFileError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what() << "\nexpected: " << expected;
    }
  }
  EXPECT_THROW(read_scene_file("/nonexistent/x.scene"), SceneFileError);
  EXPECT_THROW(read_scene_file("/dev/zero"), SceneFileError);
}

}  // namespace
}  // namespace bvh_collision
