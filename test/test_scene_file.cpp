// MoveIt `.scene` files in and out (io/scene_file.h): MoveIt's two formats read as MoveIt
// reads them, a round trip to the same doubles and the same text, the same answers as the same
// objects added one by one, and every malformed input refused by file, line and field.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <unistd.h>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/io/scene_file.h"
#include "checker_fixtures.h"
#include "scene_file_fixtures.h"
#include "planning_scenes.h"

namespace bvh_collision {
namespace {

using test::read_text;
using test::read_yaml;
using test::tetrahedron;

Transform posed(double x, double y, double z, double angle, const Vec3& axis) {
  Transform t;
  t.R = Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
  t.t = Vec3(x, y, z);
  return t;
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
      "* pole\n"  // the same id again: its shapes are added to the first's (test_scene_spellings.cpp)
      "1\n"
      "sphere\n"
      "0.05\n"
      "0.5 0 0.2\n"
      "0 0 0 1\n"
      "0 0 0 0\n"
      ".\n";
  const SceneFile b = read_text(older);
  ASSERT_EQ(b.objects.size(), 2u);
  EXPECT_EQ(b.objects[1].shapes[0].shape.kind, ObjectShape::Kind::kSphere);
  ASSERT_EQ(b.collision_objects().size(), 2u);
  EXPECT_EQ(b.collision_objects()[0].id, "pole#0");
  EXPECT_EQ(b.collision_objects()[0].shape.kind, ObjectShape::Kind::kCone);
  EXPECT_EQ(b.collision_objects()[1].id, "pole#1");
  // The subframe of the newer format is kept.
  ASSERT_EQ(a.objects[0].subframes.size(), 1u);
  EXPECT_EQ(a.objects[0].subframes[0].first, "handle");
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
    for (std::size_t c = 0; c < a.contacts.size(); ++c) {
      EXPECT_EQ(a.contacts[c].object, b.contacts[c].object) << i;
    }
    if (!a.collision) {
      EXPECT_NEAR(a.min_distance, b.min_distance, 1e-12) << i;
    }
    colliding += a.collision;
  }
  EXPECT_GT(colliding, 0) << "the scene never touched the arm: the comparison shows nothing";
}

// Each (input, message): refused with a SceneFileError whose message holds the expected text.
void expect_refusals(const std::vector<std::pair<std::string, std::string>>& cases, SceneFile (*read)(const std::string&)) {
  for (const auto& [text, expected] : cases) {
    try {
      read(text);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const SceneFileError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what() << "\nexpected: " << expected;
    }
  }
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
  expect_refusals(cases, read_text);
  EXPECT_THROW(read_scene_file("/nonexistent/x.scene"), SceneFileError);
  EXPECT_THROW(read_scene_file("/dev/zero"), SceneFileError);
}

// The same scene as every_kind(), as `rostopic echo` prints a moveit_msgs/PlanningScene (a
// cylinder's and a cone's dimensions height first, as SolidPrimitive orders them), with a robot
// state and an allowed-collision matrix.
const char* const kEveryKindYaml = R"(name: "every kind"
robot_model_name: "demo_arm"
robot_state:
  joint_state:
    header: {seq: 0, stamp: {secs: 0, nsecs: 0}, frame_id: ''}
    name: [joint1, joint2]
    position: [0.25, -0.5]
    velocity: []
    effort: []
  multi_dof_joint_state: {joint_names: [], transforms: [], twist: [], wrench: []}
  attached_collision_objects: []
  is_diff: false
world:
  collision_objects:
    - header: {frame_id: "world"}
      id: "table"
      pose:
        position: {x: 0.6, y: 0.1, z: 0.0}
        orientation: {x: 0.0, y: 0.0, z: 0.14943813247359922, w: 0.98877107793604228}
      primitives:
        - {type: 1, dimensions: [0.5, 0.8, 0.03]}
        - {type: 3, dimensions: [0.4, 0.02]}
        - {type: 4, dimensions: [0.1, 0.05]}
      primitive_poses:
        - {position: {x: 0, y: 0, z: 0.4}, orientation: {x: 0, y: 0, z: 0, w: 1}}
        - {position: {x: 0.2, y: 0.35, z: 0.2}, orientation: {x: 0, y: 0, z: 0, w: 1}}
        - position: {x: -0.1, y: 0.0, z: 0.46}
          orientation: {x: 0.24246536490574877, y: 0.24246536490574877, z: 0.0, w: 0.93937271284737889}
      meshes: []
      mesh_poses: []
      planes: []
      plane_poses: []
      operation: 0
    - id: "ball"
      primitives: [{type: 2, dimensions: [0.07]}]
      primitive_poses: [{position: {x: 0.3, y: -0.4, z: 0.6}, orientation: {x: 0, y: 0, z: 0, w: 1}}]
    - id: "part with spaces"
      pose:
        position: {x: 0.4, y: 0.4, z: 0.7}
        orientation: {x: 0.0, y: 0.3695956840164745, z: 0.3695956840164745, w: 0.8525245220595057}
      meshes:
        - vertices: [{x: 0, y: 0, z: 0}, {x: 0.1, y: 0, z: 0}, {x: 0, y: 0.1, z: 0}, {x: 0, y: 0, z: 0.1}]
          triangles: [{vertex_indices: [0, 2, 1]}, {vertex_indices: [0, 1, 3]}, {vertex_indices: [0, 3, 2]}, {vertex_indices: [1, 2, 3]}]
      mesh_poses: [{position: {x: 0, y: 0, z: 0}, orientation: {x: 0, y: 0, z: 0, w: 1}}]
  octomap:
    header: {frame_id: ''}
    origin: {position: {x: 0, y: 0, z: 0}, orientation: {x: 0, y: 0, z: 0, w: 1}}
    octomap: {header: {frame_id: ''}, binary: false, id: '', resolution: 0.0, data: []}
allowed_collision_matrix:
  entry_names: [ball, hand, table]
  entry_values:
    - enabled: [false, true, false]
    - enabled: [true, false, false]
    - enabled: [false, false, false]
  default_entry_names: []
  default_entry_values: []
object_colors: []
is_diff: false
)";

TEST(SceneFile, ReadsAPlanningSceneInYaml) {
  const SceneFile yaml = read_yaml(kEveryKindYaml);
  const SceneFile text = every_kind();
  ASSERT_EQ(yaml.objects.size(), text.objects.size());
  EXPECT_EQ(yaml.name, "every kind");
  EXPECT_EQ(yaml.objects[0].frame_id, "world");
  for (std::size_t i = 0; i < yaml.objects.size(); ++i) {
    EXPECT_EQ(yaml.objects[i].id, text.objects[i].id);

    ASSERT_EQ(yaml.objects[i].shapes.size(), text.objects[i].shapes.size());
    for (std::size_t k = 0; k < yaml.objects[i].shapes.size(); ++k) {
      const ObjectShape& a = yaml.objects[i].shapes[k].shape;
      const ObjectShape& b = text.objects[i].shapes[k].shape;
      EXPECT_EQ(a.kind, b.kind);
      EXPECT_EQ(a.size, b.size);
      EXPECT_EQ(a.radius, b.radius) << yaml.objects[i].id << " shape " << k;
      EXPECT_EQ(a.length, b.length) << yaml.objects[i].id << " shape " << k;
      // Where it is in the world (an object of one shape and no pose of its own takes its
      // shape's pose as the object's, as MoveIt does).
      const Transform a_world = yaml.objects[i].pose * yaml.objects[i].shapes[k].pose;
      const Transform b_world = text.objects[i].pose * text.objects[i].shapes[k].pose;
      EXPECT_TRUE(a_world.t.isApprox(b_world.t, 1e-12)) << yaml.objects[i].id;
    }
  }
  // The same answers as the .scene form of the same objects, with the same allowed collisions:
  // the YAML's entries (the hand may touch the ball) come with its environment.
  const CollisionChecker checker = test::demo_arm_checker();
  const Environment a = yaml.environment();
  EXPECT_TRUE(a.allowed_collisions().allowed("hand", "ball"));
  EXPECT_FALSE(a.allowed_collisions().allowed("hand", "table"));
  Environment b = text.environment();
  b.set_allowed_collisions(a.allowed_collisions());
  std::mt19937_64 rng(9);
  EnvironmentRequest request;
  request.distance = true;
  for (int i = 0; i < test::sized(200); ++i) {
    const std::vector<double> q = random_configuration(checker.model(), rng);
    const EnvironmentResult x = checker.check_environment(q.data(), a, request), y = checker.check_environment(q.data(), b, request);
    ASSERT_EQ(x.collision, y.collision) << i;
    if (!x.collision) {
      EXPECT_NEAR(x.min_distance, y.min_distance, 1e-9) << i;
    }
  }
  // The robot state and the matrix, as pairs.
  ASSERT_EQ(yaml.joint_values.size(), 2u);
  EXPECT_EQ(yaml.joint_values[1].first, "joint2");
  EXPECT_EQ(yaml.joint_values[1].second, -0.5);
  ASSERT_EQ(yaml.allowed_collisions.size(), 3u);
  EXPECT_EQ(yaml.allowed_collisions[0].a, "ball");
  EXPECT_EQ(yaml.allowed_collisions[0].b, "hand");
  EXPECT_TRUE(yaml.allowed_collisions[0].allowed);
  EXPECT_FALSE(yaml.allowed_collisions[1].allowed);
}

// Written as YAML and read back: the same objects, robot state and matrix (to 1e-15 for a
// rotation carried through a quaternion); the .scene form of the same scene read back equal too.
TEST(SceneFile, YamlRoundTrips) {
  const SceneFile original = read_yaml(kEveryKindYaml);
  std::ostringstream out;
  write_scene_yaml(original, out);
  const SceneFile back = read_yaml(out.str());
  expect_same_scene(original, back);
  EXPECT_EQ(back.objects[0].frame_id, "world");
  EXPECT_EQ(back.joint_values, original.joint_values);
  ASSERT_EQ(back.allowed_collisions.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.allowed_collisions[i].a, original.allowed_collisions[i].a);
    EXPECT_EQ(back.allowed_collisions[i].b, original.allowed_collisions[i].b);
    EXPECT_EQ(back.allowed_collisions[i].allowed, original.allowed_collisions[i].allowed);
  }
  expect_same_scene(original, read_text(text_of(back)));
  // A capsule has no MoveIt form: refused, and nothing written.
  SceneFile capsule;
  capsule.objects.push_back({"pill", Transform(), {{ObjectShape::capsule(0.1, 0.2), Transform()}}});
  const std::string path = (std::filesystem::temp_directory_path() / ("bvh_pill_" + std::to_string(::getpid()) + ".yaml")).string();
  EXPECT_THROW(write_scene_file(capsule, path), SceneFileError);
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(SceneFile, RefusesMalformedYamlByLineAndField) {
  const std::string object = "world:\n  collision_objects:\n    - id: box\n";
  const std::string pose = "      primitive_poses: [{position: {x: 0, y: 0, z: 0}, orientation: {x: 0, y: 0, z: 0, w: 1}}]\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"world: [unclosed\n", "test.yaml:2: not YAML"},
      {"- a list\n", "test.yaml:1: the document: not a PlanningScene"},
      {object + "      primitives: [{type: 1, dimensions: [0.1, 0.2]}]\n" + pose,
       "test.yaml:4: world.collision_objects[0] ('box').primitives[0].dimensions: 3 needed, 2 given"},
      {object + "      primitives: [{type: 1, dimensions: [0.1, -0.2, 0.3]}]\n" + pose, "dimensions[1]: not a positive number"},
      {object + "      primitives: [{type: 5, dimensions: [0.1]}]\n" + pose, "type '5' is not BOX (1), SPHERE (2), CYLINDER (3) or CONE (4)"},
      {object + "      primitives: [{type: 2, dimensions: [nan]}]\n" + pose, "dimensions[0]: 'nan' is not a number"},
      {object + "      primitives: [{type: 2, dimensions: [0.1]}]\n      primitive_poses: [{position: {x: 0, y: 0}, orientation: {x: 0, y: 0, z: 0, w: 1}}]\n",
       "primitive_poses[0].position.z: missing"},
      {object + "      operation: 1\n      primitives: [{type: 2, dimensions: [0.1]}]\n" + pose, "('box').operation: REMOVE and MOVE change a world"},
      {object + "      planes: [{coef: [0, 0, 1, 0]}]\n", "('box').planes: a plane (infinite) is not supported"},
      {object, "world.collision_objects[0] ('box'): no shape"},
      {object + "      meshes: [{vertices: [{x: 0, y: 0, z: 0}], triangles: [{vertex_indices: [0, 0, 1]}]}]\n      mesh_poses: [{position: {x: 0, y: 0, z: 0}, orientation: {x: 0, y: 0, z: 0, w: 1}}]\n",
       "meshes[0].triangles[0]: vertex 1 of 1"},
      {"world:\n  collision_objects:\n    - id: 'a#2'\n", "id: id 'a#2' contains '#'"},
      {"robot_state:\n  joint_state: {name: [a, b], position: [1]}\n", "robot_state.joint_state: 2 names but 1 positions"},
      {"allowed_collision_matrix:\n  entry_names: [a, b]\n  entry_values: [{enabled: [false, maybe]}, {enabled: [false, false]}]\n",
       "allowed_collision_matrix.entry_values[0][1]: 'maybe' is not true or false"},
      {"world:\n  octomap: {octomap: {data: [1, 2, 3]}}\n", "world.octomap: an octomap in a scene is not read"},
  };
  expect_refusals(cases, read_yaml);
}

}  // namespace
}  // namespace bvh_collision
