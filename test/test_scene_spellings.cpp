// Scenes as MoveIt users have them (io/scene_file.h): the benchmark spelling of
// PlanningScene YAML beside the `rostopic echo` one and `.scene` text, a generated corpus that
// must answer alike in all of them and as the same objects set one by one, MoveIt's rules for
// operations, duplicate ids and attached objects, and ids with control characters refused.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <random>
#include <sstream>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/io/scene_file.h"
#include "checker_fixtures.h"
#include "scene_file_fixtures.h"

namespace bvh_collision {
namespace {

using test::read_text;
using test::read_yaml;
using test::tetrahedron;

Transform random_pose(std::mt19937_64& rng, double spread) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Transform t;
  t.R = Eigen::AngleAxisd(3.0 * u(rng), Vec3(u(rng), u(rng), u(rng) + 1.5).normalized()).toRotationMatrix();
  t.t = Vec3(u(rng), u(rng), u(rng) + 1.0) * spread;
  return t;
}

// A scene of every kind around the demo arm: posed objects of one to three shapes (boxes,
// spheres, cylinders, cones, meshes), some with subframes.
SceneFile random_scene(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> size(0.03, 0.25);
  SceneFile scene;
  scene.name = "corpus " + std::to_string(seed);
  const int objects = 2 + static_cast<int>(rng() % 6);
  for (int i = 0; i < objects; ++i) {
    SceneObject o;
    o.id = "object_" + std::to_string(i);
    o.pose = random_pose(rng, 0.45);
    const int shapes = 1 + static_cast<int>(rng() % 3);
    for (int k = 0; k < shapes; ++k) {
      ObjectShape s;
      switch (rng() % 5) {
        case 0: s = ObjectShape::box({size(rng), size(rng), size(rng)}); break;
        case 1: s = ObjectShape::sphere(size(rng)); break;
        case 2: s = ObjectShape::cylinder(size(rng), 2 * size(rng)); break;
        case 3: s = ObjectShape::cone(size(rng), 2 * size(rng)); break;
        default: s = ObjectShape::triangles(tetrahedron(2 * size(rng))); break;
      }
      o.shapes.push_back({s, random_pose(rng, 0.1)});
    }
    // Primitives first, as a CollisionObject message holds them: every spelling numbers them alike.
    std::stable_partition(o.shapes.begin(), o.shapes.end(), [](const SceneShape& x) { return x.shape.kind != ObjectShape::Kind::kMesh; });
    if (rng() % 3 == 0) o.subframes.emplace_back("tip", random_pose(rng, 0.05));
    scene.objects.push_back(std::move(o));
  }
  return scene;
}

void emit_numbers(YAML::Emitter& e, const std::vector<double>& v) {
  e << YAML::Flow << YAML::BeginSeq;
  for (const double x : v) e << x;
  e << YAML::EndSeq;
}

void emit_pose_as_lists(YAML::Emitter& e, const Transform& t) {
  const Eigen::Quaterniond q(t.R);
  e << YAML::BeginMap << YAML::Key << "position" << YAML::Value;
  emit_numbers(e, {t.t.x(), t.t.y(), t.t.z()});
  e << YAML::Key << "orientation" << YAML::Value;
  emit_numbers(e, {q.x(), q.y(), q.z(), q.w()});
  e << YAML::EndMap;
}

// The spelling of the public benchmark's writer: types by name (in mixed case here), points and
// quaternions as lists, mesh triangles as bare lists, matrix rows as bare lists, in block style
// or in flow style throughout.
std::string benchmark_spelling(const SceneFile& scene, bool flow) {
  static const char* const kNames[] = {"box", "Sphere", "CYLINDER", "cone"};
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  if (flow) e << YAML::Flow;
  e << YAML::BeginMap << YAML::Key << "name" << YAML::Value << scene.name;
  e << YAML::Key << "world" << YAML::Value << YAML::BeginMap << YAML::Key << "collision_objects" << YAML::Value << YAML::BeginSeq;
  for (const SceneObject& o : scene.objects) {
    e << YAML::BeginMap << YAML::Key << "header" << YAML::Value << YAML::BeginMap << YAML::Key << "frame_id" << YAML::Value
      << "base_link" << YAML::EndMap;
    e << YAML::Key << "id" << YAML::Value << o.id << YAML::Key << "pose" << YAML::Value;
    emit_pose_as_lists(e, o.pose);
    for (const bool meshes : {false, true}) {
      e << YAML::Key << (meshes ? "meshes" : "primitives") << YAML::Value << YAML::BeginSeq;
      for (const SceneShape& s : o.shapes) {
        if ((s.shape.kind == ObjectShape::Kind::kMesh) != meshes) continue;
        if (meshes) {
          e << YAML::BeginMap << YAML::Key << "vertices" << YAML::Value << YAML::BeginSeq;
          for (const Vec3& v : s.shape.mesh->vertices) emit_numbers(e, {v.x(), v.y(), v.z()});
          e << YAML::EndSeq << YAML::Key << "triangles" << YAML::Value << YAML::BeginSeq;
          for (const auto& t : s.shape.mesh->triangles) emit_numbers(e, {double(t[0]), double(t[1]), double(t[2])});
          e << YAML::EndSeq << YAML::EndMap;
          continue;
        }
        const ObjectShape::Kind kind = s.shape.kind;
        const int name = kind == ObjectShape::Kind::kBox ? 0 : kind == ObjectShape::Kind::kSphere ? 1 : kind == ObjectShape::Kind::kCylinder ? 2 : 3;
        e << YAML::BeginMap << YAML::Key << "type" << YAML::Value << kNames[name] << YAML::Key << "dimensions" << YAML::Value;
        if (name == 0) emit_numbers(e, {s.shape.size.x(), s.shape.size.y(), s.shape.size.z()});
        if (name == 1) emit_numbers(e, {s.shape.radius});
        if (name >= 2) emit_numbers(e, {s.shape.length, s.shape.radius});
        e << YAML::EndMap;
      }
      e << YAML::EndSeq << YAML::Key << (meshes ? "mesh_poses" : "primitive_poses") << YAML::Value << YAML::BeginSeq;
      for (const SceneShape& s : o.shapes) {
        if ((s.shape.kind == ObjectShape::Kind::kMesh) == meshes) emit_pose_as_lists(e, s.pose);
      }
      e << YAML::EndSeq;
    }
    if (!o.subframes.empty()) {
      e << YAML::Key << "subframe_names" << YAML::Value << YAML::BeginSeq;
      for (const auto& [name, pose] : o.subframes) e << name;
      e << YAML::EndSeq << YAML::Key << "subframe_poses" << YAML::Value << YAML::BeginSeq;
      for (const auto& [name, pose] : o.subframes) emit_pose_as_lists(e, pose);
      e << YAML::EndSeq;
    }
    e << YAML::EndMap;
  }
  e << YAML::EndSeq << YAML::EndMap;
  e << YAML::Key << "allowed_collision_matrix" << YAML::Value << YAML::BeginMap << YAML::Key << "entry_names" << YAML::Value
    << YAML::Flow << std::vector<std::string>{"hand", scene.objects[0].id} << YAML::Key << "entry_values" << YAML::Value
    << YAML::BeginSeq << YAML::Flow << std::vector<bool>{false, true} << YAML::Flow << std::vector<bool>{true, false} << YAML::EndSeq
    << YAML::EndMap;
  e << YAML::EndMap;
  return e.c_str();
}

// The scene's objects set one by one as set_collision_object sets them (each shape at the
// object's pose times its own, named id or id#k).
Environment set_one_by_one(const SceneFile& scene) {
  Environment env(0.05);
  for (const SceneObject& o : scene.objects) {
    for (std::size_t k = 0; k < o.shapes.size(); ++k) {
      env.add_object(o.shapes.size() == 1 ? o.id : o.id + "#" + std::to_string(k), o.shapes[k].shape, o.pose * o.shapes[k].pose);
    }
  }
  NamedAllowedCollisions acm;
  acm.set_entry("hand", scene.objects[0].id, true);
  env.set_allowed_collisions(std::move(acm));
  return env;
}

// Every environment answers every state alike: collision, the objects touched, the distance.
void expect_same_answers(const CollisionChecker& checker, const std::vector<const Environment*>& worlds, std::uint64_t seed,
                         int& colliding) {
  std::mt19937_64 rng(seed);
  EnvironmentRequest request;
  request.all_links = true;
  request.distance = true;
  for (int i = 0; i < test::sized(60); ++i) {
    const std::vector<double> q = random_configuration(checker.model(), rng);
    const EnvironmentResult a = checker.check_environment(q.data(), *worlds[0], request);
    std::vector<std::string> touched;
    for (const EnvironmentContact& c : a.contacts) touched.push_back(checker.model().links()[c.link].name + ":" + c.object);
    std::sort(touched.begin(), touched.end());
    for (std::size_t w = 1; w < worlds.size(); ++w) {
      const EnvironmentResult b = checker.check_environment(q.data(), *worlds[w], request);
      ASSERT_EQ(a.collision, b.collision) << "world " << w << " state " << i;
      std::vector<std::string> other;
      for (const EnvironmentContact& c : b.contacts) other.push_back(checker.model().links()[c.link].name + ":" + c.object);
      std::sort(other.begin(), other.end());
      ASSERT_EQ(touched, other) << "world " << w << " state " << i;
      if (!a.collision) {
        ASSERT_NEAR(a.min_distance, b.min_distance, 1e-9) << "world " << w << " state " << i;
      }
    }
    colliding += a.collision;
  }
}

// The generated corpus: each scene written in both YAML spellings (block and flow) and as .scene
// text, read back, placed (frame base_link is the demo arm's root) and checked against the same
// objects set one by one. On main the benchmark spelling was refused ("'box' is not a number").
TEST(SceneSpellings, EverySpellingOfACorpusAnswersAlike) {
  const CollisionChecker checker = test::demo_arm_checker();
  const SceneFrameLookup root = [](const std::string& frame) -> std::optional<Transform> {
    if (frame == "base_link") return Transform::Identity();
    return std::nullopt;
  };
  int colliding = 0, states = 0;
  for (int k = 0; k < test::sized(24); ++k) {
    SceneFile scene = random_scene(900 + k);
    std::ostringstream rostopic, text;
    write_scene_yaml(scene, rostopic);
    write_scene_text(scene, text);
    std::vector<SceneFile> read = {read_yaml(rostopic.str()), read_yaml(benchmark_spelling(scene, false)),
                                   read_yaml(benchmark_spelling(scene, true)), read_text(text.str())};
    for (SceneFile& s : read) {
      ASSERT_EQ(s.objects.size(), scene.objects.size());
      EXPECT_EQ(s.objects[0].subframes.size(), scene.objects[0].subframes.size());
      place_in_world(s, root);
    }
    // The .scene text and the rostopic spelling hold no matrix here: it is the benchmark's.
    for (SceneFile* s : {&read[0], &read[3]}) s->allowed_collisions = read[1].allowed_collisions;
    std::vector<Environment> worlds;
    for (const SceneFile& s : read) worlds.push_back(s.environment());
    worlds.push_back(set_one_by_one(scene));
    EXPECT_TRUE(worlds[1].allowed_collisions().allowed("hand", scene.objects[0].id));
    std::vector<const Environment*> all;
    for (const Environment& w : worlds) all.push_back(&w);
    expect_same_answers(checker, all, 7 + k, colliding);
    states += test::sized(60);
  }
  EXPECT_GT(colliding, states / 10) << "too few states touch the corpus: the comparison shows little";
  EXPECT_LT(colliding, states * 9 / 10);
}

// The public benchmark's scene as its writer spells it (types by name, poses as lists, the
// object's own pose, subframes), placed in its frame.
TEST(SceneSpellings, ReadsTheBenchmarkWritersScene) {
  const SceneFile scene = read_yaml(R"(fixed_frame_transforms:
  - child_frame_id: base_link
    header: {frame_id: base_link}
    transform: {translation: [0, 0, 0], rotation: [0, 0, 0, 1]}
name: (noname)+
robot_model_name: demo_arm
robot_state:
  joint_state:
    name: [joint1, joint2]
    position: [0.1, 0.2]
world:
  collision_objects:
    - header:
        frame_id: base_link
      id: Can1
      pose:
        position: [0.54, 0.36, -0.38]
        orientation: [0, 0, 0.074, 0.997]
      primitives:
        - type: cylinder
          dimensions: [0.14, 0.03]
      primitive_poses:
        - position: [0, 0, 0]
          orientation: [0, 0, 0, 1]
      subframe_names: [top]
      subframe_poses:
        - position: [0, 0, 0.07]
          orientation: [0, 0, 0, 1]
    - header: {frame_id: Can1/top}
      id: lid
      primitives: [{type: BOX, dimensions: [0.06, 0.06, 0.01]}]
      primitive_poses: [{position: [0, 0, 0.005], orientation: [0, 0, 0, 1]}]
allowed_collision_matrix:
  entry_names: [Can1, hand]
  entry_values:
    - [false, true]
    - [true, false]
)");
  ASSERT_EQ(scene.objects.size(), 2u);
  EXPECT_EQ(scene.objects[0].shapes[0].shape.kind, ObjectShape::Kind::kCylinder);
  EXPECT_EQ(scene.objects[0].shapes[0].shape.radius, 0.03);
  EXPECT_EQ(scene.objects[0].shapes[0].shape.length, 0.14);
  EXPECT_EQ(scene.objects[1].shapes[0].shape.kind, ObjectShape::Kind::kBox);
  ASSERT_EQ(scene.allowed_collisions.size(), 1u);
  EXPECT_TRUE(scene.allowed_collisions[0].allowed);
  EXPECT_TRUE(scene.warnings.empty()) << scene.warnings[0];
  SceneFile placed = scene;
  place_in_world(placed, [](const std::string& frame) -> std::optional<Transform> {
    if (frame == "base_link") return Transform::Identity();
    return std::nullopt;
  });
  // The lid sits on the can's subframe: 7 cm above the can's centre, along its axis.
  const std::vector<CollisionObject> objects = placed.collision_objects();
  ASSERT_EQ(objects.size(), 2u);
  const Vec3 axis = objects[0].pose.R.col(2);
  EXPECT_TRUE(objects[1].pose.t.isApprox(objects[0].pose.t + 0.075 * axis, 1e-9)) << objects[1].pose.t.transpose();
}

// A .scene of two entries of one id: MoveIt (before 1.1.12) adds the second's shapes to the
// object, so the first's box is still there; on main the second replaced the first and a state
// touching the box was answered free. The YAML reader merges two ADD entries of one id alike.
TEST(SceneSpellings, TwoEntriesOfOneIdKeepEveryShape) {
  const std::string text =
      "dup\n* pillar\n0 0 0\n0 0 0 1\n1\nbox\n0.1 0.1 2\n0.3 0 1\n0 0 0 1\n0 0 0 0\n0\n"
      "* pillar\n0 0 0\n0 0 0 1\n1\nsphere\n0.05\n-0.6 0 0.3\n0 0 0 1\n0 0 0 0\n0\n.\n";
  const SceneFile scene = read_text(text);
  ASSERT_EQ(scene.warnings.size(), 1u);
  EXPECT_NE(scene.warnings[0].find("test.scene:12: object 'pillar' is also at line 2"), std::string::npos) << scene.warnings[0];
  const Environment env = scene.environment();
  ASSERT_EQ(env.objects().size(), 2u);
  EXPECT_NE(env.find_object("pillar#0"), nullptr);
  EXPECT_NE(env.find_object("pillar#1"), nullptr);
  // A state that meets the first entry's box and not the second's sphere: answered free on main.
  const CollisionChecker checker = test::demo_arm_checker();
  Environment box_only(0.05), sphere_only(0.05);
  box_only.add_object("pillar", ObjectShape::box({0.1, 0.1, 2}), Transform::Translation({0.3, 0, 1}));
  sphere_only.add_object("pillar", ObjectShape::sphere(0.05), Transform::Translation({-0.6, 0, 0.3}));
  std::mt19937_64 rng(4);
  std::vector<double> q;
  for (int i = 0; i < 10000 && q.empty(); ++i) {
    const std::vector<double> c = random_configuration(checker.model(), rng);
    if (checker.check_environment(c.data(), box_only).collision && !checker.check_environment(c.data(), sphere_only).collision) q = c;
  }
  ASSERT_FALSE(q.empty());
  EXPECT_TRUE(checker.check_environment(q.data(), env).collision);
  const std::string yaml =
      "world:\n  collision_objects:\n"
      "    - {id: pillar, primitives: [{type: box, dimensions: [0.1, 0.1, 2]}], primitive_poses: [{position: [0.3, 0, 1], orientation: [0, 0, 0, 1]}]}\n"
      "    - {id: pillar, primitives: [{type: sphere, dimensions: [0.05]}], primitive_poses: [{position: [-0.6, 0, 0.3], orientation: [0, 0, 0, 1]}]}\n";
  const SceneFile twice = read_yaml(yaml);
  ASSERT_EQ(twice.warnings.size(), 1u);
  const Environment env2 = twice.environment();
  EXPECT_EQ(env2.objects().size(), 2u);
  EXPECT_TRUE(checker.check_environment(q.data(), env2).collision);
}

// A diff's operations as MoveIt applies them to the world there; outside a diff REMOVE and MOVE
// are refused by name.
TEST(SceneSpellings, OperationsApplyAsMoveItAppliesThem) {
  Environment env(0.05);
  CollisionObject keep = make_collision_object("keep", ObjectShape::sphere(0.1), Transform::Translation({2, 0, 0}));
  keep.frame = Transform::Translation({2, 0, 0});  // as set_collision_object sets an object at (2, 0, 0)
  env.add_object(keep);
  CollisionObject crate = make_collision_object("crate", ObjectShape::box({0.2, 0.2, 0.2}), Transform::Translation({1, 0, 0}));
  crate.frame = Transform::Translation({1, 0, 0});
  env.add_object(crate);
  env.add_object("gone", ObjectShape::sphere(0.1), Transform::Translation({3, 0, 0}));
  const SceneFile diff = read_yaml(R"(is_diff: true
world:
  collision_objects:
    - {id: crate, operation: append, primitives: [{type: sphere, dimensions: [0.05]}], primitive_poses: [{position: [0, 0, 0.3], orientation: [0, 0, 0, 1]}]}
    - {id: keep, operation: MOVE, pose: {position: [2, 1, 0], orientation: [0, 0, 0, 1]}}
    - {id: gone, operation: 1}
    - {id: never_there, operation: remove}
    - {id: fresh, primitives: [{type: 2, dimensions: [0.1]}], primitive_poses: [{position: [0, 0, 5], orientation: [0, 0, 0, 1]}]}
)");
  std::vector<std::string> warnings;
  apply_scene_objects(diff, env, warnings);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("object 'never_there' (line 7): REMOVE of an object the world does not hold"), std::string::npos) << warnings[0];
  EXPECT_EQ(env.find_object("gone"), nullptr);
  ASSERT_NE(env.find_object("crate#1"), nullptr);
  // APPEND: in the existing object's frame (at x = 1), as MoveIt's World adds it.
  EXPECT_TRUE(env.find_object("crate#1")->pose.t.isApprox(Vec3(1, 0, 0.3)));
  EXPECT_TRUE(env.find_object("keep")->pose.t.isApprox(Vec3(2, 1, 0)));
  EXPECT_TRUE(env.find_object("fresh")->pose.t.isApprox(Vec3(0, 0, 5)));
  // A MOVE of an object that is not there, or with another count of shape poses: refused.
  for (const std::string& op : {std::string("{id: nowhere, operation: move, pose: {position: [0, 0, 0], orientation: [0, 0, 0, 1]}}"),
                                std::string("{id: crate, operation: move, primitives: [{type: sphere, dimensions: [1]}], "
                                            "primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]}")}) {
    Environment copy = env;
    EXPECT_THROW(apply_scene_objects(read_yaml("is_diff: true\nworld:\n  collision_objects:\n    - " + op + "\n"), copy, warnings), SceneFileError) << op;
  }
  try {
    read_yaml("world:\n  collision_objects:\n    - {id: crate, operation: remove}\n");
    ADD_FAILURE() << "a REMOVE outside a diff was read";
  } catch (const SceneFileError& e) {
    EXPECT_NE(std::string(e.what()).find("operation: REMOVE and MOVE change a world that is there: only a diff"), std::string::npos) << e.what();
  }
}

// An object in the hand (robot_state.attached_collision_objects): read, hung from its link, checked
// as part of the robot, and written back. On main the reader refused it ("not supported yet").
TEST(SceneSpellings, AnObjectInTheHandLoadsAttached) {
  const std::string yaml = R"(name: holding
robot_state:
  attached_collision_objects:
    - link_name: hand
      touch_links: [finger_left, finger_right]
      object:
        id: bar
        header: {frame_id: hand}
        primitives: [{type: box, dimensions: [0.02, 0.8, 0.02]}]
        primitive_poses: [{position: [0, 0, 0.06], orientation: [0, 0, 0, 1]}]
world:
  collision_objects:
    - {id: post, primitives: [{type: cylinder, dimensions: [2, 0.03]}], primitive_poses: [{position: [0, 0.35, 1], orientation: [0, 0, 0, 1]}]}
)";
  SceneFile scene = read_yaml(yaml);
  ASSERT_EQ(scene.attached.size(), 1u);
  EXPECT_EQ(scene.attached[0].link, "hand");
  EXPECT_EQ(scene.attached[0].touch_links.size(), 2u);
  place_in_world(scene, [](const std::string&) -> std::optional<Transform> { return std::nullopt; });
  const Environment env = scene.environment();
  ASSERT_EQ(env.attached().size(), 1u);
  EXPECT_EQ(env.find_object("bar"), nullptr);
  const CollisionChecker checker = test::demo_arm_checker();
  const CollisionChecker holding = checker.carrying(env, false);
  // Upright, the hand's bar (0.8 m across, at the top of the arm, about 1.2 m up) reaches the post
  // 0.35 m away; without the bar the arm is clear of it.
  const std::vector<double> q(checker.model().variable_count(), 0.0);
  EnvironmentRequest request;
  request.all_links = true;
  const EnvironmentResult held = holding.check_environment(q.data(), env, request);
  ASSERT_TRUE(held.collision);
  EXPECT_EQ(holding.model().links()[held.contacts[0].link].name, "bar");
  Environment empty_hand = env;
  empty_hand.detach("bar");
  EXPECT_FALSE(checker.check_environment(q.data(), empty_hand).collision);
  // Written as YAML and read again: still in the hand.
  std::ostringstream out;
  write_scene_yaml(scene, out);
  const SceneFile back = read_yaml(out.str());
  ASSERT_EQ(back.attached.size(), 1u);
  EXPECT_EQ(back.attached[0].object.id, "bar");
  EXPECT_EQ(back.attached[0].touch_links, scene.attached[0].touch_links);
}

// Ids with a NUL or an ESC were accepted from a .scene file (a mesh name with one was refused):
// every reader refuses them by name, as make_collision_object and attach do.
TEST(SceneSpellings, IdsWithControlCharactersAreRefused) {
  for (const std::string& id : {std::string("ta") + '\0' + "ble", std::string("\x1b[2Jtable"), std::string("tab\x7f")}) {
    const std::string text = "scene\n* " + id + "\n0 0 0\n0 0 0 1\n1\nsphere\n0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n.\n";
    try {
      read_text(text);
      ADD_FAILURE() << "read an id with a control character";
    } catch (const SceneFileError& e) {
      EXPECT_NE(std::string(e.what()).find("test.scene:2: object id '"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("holds a control character"), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\x1b'), std::string::npos) << "the message shows the ESC escaped";
    }
    // YAML's double-quoted \xHH escapes put the same byte in the id.
    const std::string yaml = "world:\n  collision_objects:\n    - {id: \"" + printable_id(id) +
                             "\", primitives: [{type: sphere, dimensions: [0.1]}], primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]}\n";
    EXPECT_THROW(read_yaml(yaml), SceneFileError) << yaml;
    EXPECT_THROW(make_collision_object(id, ObjectShape::sphere(0.1), Transform()), std::invalid_argument);
    EXPECT_THROW(make_collision_object("ok#" + id, ObjectShape::sphere(0.1), Transform()), std::invalid_argument);
    Environment env(0.05);
    AttachedBody body{id, "hand", {}, {make_collision_object("x", ObjectShape::sphere(0.1), Transform())}};
    EXPECT_THROW(env.attach(body), std::invalid_argument);
  }
  EXPECT_EQ(object_id_problem("plain id"), "");
  EXPECT_NE(object_id_problem("a\tb").find("holds a control character (0x09 at byte 1)"), std::string::npos);
}

// Either spelling's mistakes are refused by name and line, and what MoveIt would log and skip
// is a warning.
TEST(SceneSpellings, RefusalsAndWarningsNameTheField) {
  const std::string object = "world:\n  collision_objects:\n    - id: box\n";
  const std::vector<std::pair<std::string, std::string>> refused = {
      {object + "      primitives: [{type: torus, dimensions: [0.1]}]\n", "type 'torus' is not BOX (1), SPHERE (2), CYLINDER (3) or CONE (4)"},
      {object + "      primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}]\n      primitive_poses: [{position: [0, 0], orientation: [0, 0, 0, 1]}]\n",
       "test.yaml:5: world.collision_objects[0] ('box').primitive_poses[0].position: a list of 2 where 3 (xyz) belong"},
      {object + "      primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}]\n      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 1]}]\n",
       "orientation: a list of 3 where 4 (xyzw) belong"},
      {object + "      operation: explode\n      primitives: [{type: box, dimensions: [0.1, 0.1, 0.1]}]\n",
       "'explode' is not ADD (0), REMOVE (1), APPEND (2) or MOVE (3)"},
      {object + "      primitives: [{type: sphere, dimensions: [0.1]}, {type: sphere, dimensions: [0.2]}]\n      primitive_poses: "
                "[{position: [0, 0, 0]}, {position: [1, 0, 0]}, {position: [2, 0, 0]}]\n",
       "2 primitives but 3 primitive_poses"},
      {object + "      meshes: [{vertices: [[0, 0, 0], [1, 0, 0], [0, 1, 0]], triangles: [[0, 1, 3]]}]\n", "meshes[0].triangles[0]: vertex 3 of 3"},
      {object + "      meshes: [{resource: 'package://x/y.stl'}]\n", "meshes[0].resource: a mesh by file is not read here"},
      {"allowed_collision_matrix:\n  entry_names: [a, b]\n  entry_values: [[false, maybe], [false, false]]\n",
       "allowed_collision_matrix.entry_values[0][1]: 'maybe' is not true or false"},
      {"robot_state:\n  attached_collision_objects: [{link_name: hand}]\n", "robot_state.attached_collision_objects[0].object: missing"},
  };
  for (const auto& [text, expected] : refused) {
    try {
      read_yaml(text);
      ADD_FAILURE() << "accepted:\n" << text;
    } catch (const SceneFileError& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what() << "\nexpected: " << expected;
    }
  }
  const std::string at_origin = "      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n";
  const std::vector<std::pair<std::string, std::string>> warned = {
      {object + "      primitives: [{type: sphere, dimensions: [0.1, 7]}]\n" + at_origin, "dimensions: 2 given, the first 1 used"},
      {object + "      primitives: [{type: sphere, dimensions: [0.1]}, {type: sphere, dimensions: [0.1]}]\n" + at_origin,
       "2 primitives but 1 primitive_poses: the rest at the object's origin"},
      {object + "      primitives: [{type: sphere, dimensions: [0.1]}]\n      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 3]}]\n",
       "not a unit quaternion (norm 3): normalised"},
      {object + "      primitives: [{type: sphere, dimensions: [0.1]}]\n      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 0]}]\n",
       "a zero quaternion, taken as no rotation"},
      {"allowed_collision_matrix:\n  entry_names: [a, b]\n  entry_values: [[false, true]]\n", "2 entry_names but 1 entry_values: the matrix is ignored"},
      {"link_padding: [{link_name: hand, padding: 0.02}]\n", "link_padding[0]: not applied"},
      {"colour: red\n", "colour: not a PlanningScene field: ignored"},
  };
  for (const auto& [text, expected] : warned) {
    const SceneFile s = read_yaml(text);
    ASSERT_EQ(s.warnings.size(), 1u) << text;
    EXPECT_NE(s.warnings[0].find(expected), std::string::npos) << s.warnings[0] << "\nexpected: " << expected;
  }
}

}  // namespace
}  // namespace bvh_collision
