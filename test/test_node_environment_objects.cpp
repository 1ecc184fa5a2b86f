// Launch test (one binary with test_node_environment.cpp, node_environment_fixture.h): the node's
// collision objects as a planning scene holds them: the scene file it starts with, scenes loaded
// and saved, allowed collisions with objects, an object attached to the hand.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include <std_srvs/Empty.h>

#include "bvh_collision/AttachObject.h"
#include "bvh_collision/CastRay.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/ClearBox.h"
#include "bvh_collision/DetachObject.h"
#include "bvh_collision/LoadScene.h"
#include "bvh_collision/RemoveCollisionObject.h"
#include "bvh_collision/SaveScene.h"
#include "bvh_collision/SetAllowedCollisions.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"
#include "node_environment_fixture.h"

namespace bvh_collision::test {
namespace {

TEST_F(NodeEnvironment, StartsWithTheObjectsOfItsSceneFile) {
  ASSERT_EQ(start_scene_hit_.error, "");
  EXPECT_TRUE(start_scene_hit_.hit);
  EXPECT_EQ(start_scene_hit_.body, "start_box");
  EXPECT_NEAR(start_scene_hit_.distance, 0.75, 1e-9);
}

// A MoveIt .scene file (every primitive kind, a mesh, an object of three shapes, a rotated pose)
// loaded through load_scene answers exactly as the same objects set through
// set_collision_object; save_scene writes them back so that loading that file answers alike; a
// malformed file changes nothing; merge keeps the objects already there.
TEST_F(NodeEnvironment, ScenesLoadAsSetCollisionObjectMakesThemAndSaveBack) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("bvh_scenes_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string tetra = "mesh\n4 4\n0 0 0\n0.1 0 0\n0 0.1 0\n0 0 0.1\n0 2 1\n0 1 3\n0 3 2\n1 2 3\n";
  std::ofstream((dir / "two_ways.scene").string())
      << "two ways\n"
      << "* post\n0.6 0 0.5\n0 0 0 1\n3\n"
      << "cone\n0.1 0.4\n0 0 0\n0 0 0 1\n0 0 0 0\n"
      << "box\n0.3 0.3 0.1\n0 0 -0.25\n0 0 0 1\n0 0 0 0\n"
      << tetra << "0 0.3 0.1\n0 0 0 1\n0 0 0 0\n0\n"
      << "* ball\n0 -0.5 0.6\n0 0 0 1\n1\nsphere\n0.08\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n"
      << "* pole\n-0.4 0.3 0.5\n0 0 0 1\n1\ncylinder\n0.03 0.6\n0 0 0\n0.38268343236508978 0 0 0.92387953251128674\n0 0 0 0\n0\n"
      << ".\n";
  LoadScene::Request load;
  load.path = (dir / "two_ways.scene").string();
  const LoadScene::Response loaded = call<LoadScene>("load_scene", load).response;
  ASSERT_EQ(loaded.error, "");
  EXPECT_EQ(loaded.name, "two ways");
  EXPECT_EQ(loaded.objects, 3u);
  EXPECT_EQ(loaded.shapes, 5u);

  // Answers over random states: validity, the nearest distance, the first contact's object.
  std::mt19937_64 rng(17);
  std::vector<std::vector<double>> states;
  for (int i = 0; i < 150; ++i) states.push_back(random_configuration(checker().model(), rng));
  auto answers = [&] {
    std::vector<std::string> out;
    for (const auto& q : states) {
      CheckState::Request r = state_request(checker(), q);
      r.checks = CheckState::Request::ENVIRONMENT;
      r.max_contacts = 1;
      r.distance = true;
      const CheckState::Response a = call<CheckState>("check_state", r).response;
      std::ostringstream line;
      line << static_cast<int>(a.valid) << " " << std::setprecision(12) << a.min_distance << " " << (a.contacts.empty() ? "-" : a.contacts[0].body_b);
      out.push_back(line.str() + a.error);
    }
    return out;
  };
  const std::vector<std::string> from_scene = answers();
  EXPECT_GT(std::count_if(from_scene.begin(), from_scene.end(), [](const std::string& a) { return a[0] == '0'; }), 5)
      << "the scene should touch the arm in some states";

  // The same objects through set_collision_object.
  std_srvs::Empty empty;
  ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
  using shape_msgs::SolidPrimitive;
  SetCollisionObject::Request post = cone_on_plinth();
  shape_msgs::Mesh mesh;
  for (const Vec3& v : {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0), Vec3(0, 0, 0.1)}) {
    geometry_msgs::Point p;
    p.x = v.x(), p.y = v.y(), p.z = v.z();
    mesh.vertices.push_back(p);
  }
  for (const auto& t : std::vector<std::array<std::uint32_t, 3>>{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}) {
    shape_msgs::MeshTriangle tri;
    tri.vertex_indices = {t[0], t[1], t[2]};
    mesh.triangles.push_back(tri);
  }
  post.meshes = {mesh};
  post.mesh_poses = {pose_at(Vec3(0.0, 0.3, 0.1))};
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", post).response.error, "");
  SetCollisionObject::Request ball;
  ball.id = "ball";
  ball.pose = pose_at(Vec3(0.0, -0.5, 0.6));
  ball.primitives = {solid(SolidPrimitive::SPHERE, {0.08})};
  ball.primitive_poses = {pose_at(Vec3::Zero())};
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", ball).response.error, "");
  SetCollisionObject::Request pole;
  pole.id = "pole";
  pole.pose = pose_at(Vec3(-0.4, 0.3, 0.5));
  pole.primitives = {solid(SolidPrimitive::CYLINDER, {0.6, 0.03})};
  geometry_msgs::Pose tilted = pose_at(Vec3::Zero());
  tilted.orientation.x = 0.38268343236508978, tilted.orientation.w = 0.92387953251128674;
  pole.primitive_poses = {tilted};
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", pole).response.error, "");
  EXPECT_EQ(answers(), from_scene);

  // Saved and loaded back (replacing): the same answers.
  SaveScene::Request save;
  save.path = (dir / "saved.scene").string();
  save.name = "saved";
  ASSERT_EQ(call<SaveScene>("save_scene", save).response.error, "");
  ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
  load.path = save.path;
  const LoadScene::Response reloaded = call<LoadScene>("load_scene", load).response;
  ASSERT_EQ(reloaded.error, "");
  EXPECT_EQ(reloaded.name, "saved");
  EXPECT_EQ(reloaded.objects, 3u);
  EXPECT_EQ(answers(), from_scene);
  // And as PlanningScene YAML.
  save.path = (dir / "saved.yaml").string();
  ASSERT_EQ(call<SaveScene>("save_scene", save).response.error, "");
  ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
  load.path = save.path;
  ASSERT_EQ(call<LoadScene>("load_scene", load).response.error, "");
  EXPECT_EQ(answers(), from_scene);
  // And as the MoveIt benchmarking tools write it: types by name, poses as lists, triangles as
  // bare lists, flow style (refused on main: "'cone' is not a number").
  std::ofstream((dir / "benchmark.yaml").string())
      << "name: two ways\nworld:\n  collision_objects:\n"
      << "    - {header: {frame_id: world}, id: post, pose: {position: [0.6, 0, 0.5], orientation: [0, 0, 0, 1]},\n"
      << "       primitives: [{type: cone, dimensions: [0.4, 0.1]}, {type: Box, dimensions: [0.3, 0.3, 0.1]}],\n"
      << "       primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}, {position: [0, 0, -0.25], orientation: [0, 0, 0, 1]}],\n"
      << "       meshes: [{vertices: [[0, 0, 0], [0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]], triangles: [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]}],\n"
      << "       mesh_poses: [{position: [0, 0.3, 0.1], orientation: [0, 0, 0, 1]}]}\n"
      << "    - {id: ball, primitives: [{type: SPHERE, dimensions: [0.08]}], primitive_poses: [{position: [0, -0.5, 0.6], orientation: [0, 0, 0, 1]}]}\n"
      << "    - {id: pole, pose: {position: [-0.4, 0.3, 0.5], orientation: [0, 0, 0, 1]}, primitives: [{type: cylinder, dimensions: [0.6, 0.03]}],\n"
      << "       primitive_poses: [{position: [0, 0, 0], orientation: [0.38268343236508978, 0, 0, 0.92387953251128674]}]}\n";
  ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
  load.path = (dir / "benchmark.yaml").string();
  const LoadScene::Response spelled = call<LoadScene>("load_scene", load).response;
  ASSERT_EQ(spelled.error, "");
  EXPECT_EQ(spelled.shapes, 5u);
  EXPECT_EQ(answers(), from_scene);
  // The .scene split in two entries of the id "post": MoveIt (before 1.1.12) adds the second's
  // shapes to the first's; so do we (on main the second replaced the first).
  std::ofstream((dir / "split.scene").string())
      << "two ways\n"
      << "* post\n0.6 0 0.5\n0 0 0 1\n2\n"
      << "cone\n0.1 0.4\n0 0 0\n0 0 0 1\n0 0 0 0\n"
      << "box\n0.3 0.3 0.1\n0 0 -0.25\n0 0 0 1\n0 0 0 0\n0\n"
      << "* post\n0.6 0 0.5\n0 0 0 1\n1\n" << tetra << "0 0.3 0.1\n0 0 0 1\n0 0 0 0\n0\n"
      << "* ball\n0 -0.5 0.6\n0 0 0 1\n1\nsphere\n0.08\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n"
      << "* pole\n-0.4 0.3 0.5\n0 0 0 1\n1\ncylinder\n0.03 0.6\n0 0 0\n0.38268343236508978 0 0 0.92387953251128674\n0 0 0 0\n0\n"
      << ".\n";
  load.path = (dir / "split.scene").string();
  const LoadScene::Response split = call<LoadScene>("load_scene", load).response;
  ASSERT_EQ(split.error, "");
  EXPECT_NE(split.warning.find("split.scene:17: object 'post' is also at line 2"), std::string::npos) << split.warning;
  EXPECT_EQ(answers(), from_scene);
  // Ids with a control character: refused by name by every service that takes one.
  const std::string escape = std::string("crate\x1b[2J");
  SetCollisionObject::Request bad_id = ball;
  bad_id.id = escape;
  EXPECT_NE(call<SetCollisionObject>("set_collision_object", bad_id).response.error.find("id 'crate\\x1B[2J' holds a control character"),
            std::string::npos);
  RemoveCollisionObject::Request remove_bad;
  remove_bad.id = std::string("ba") + '\0' + "ll";
  EXPECT_NE(call<RemoveCollisionObject>("remove_collision_object", remove_bad).response.error.find("holds a control character"), std::string::npos);
  std::ofstream((dir / "escape.scene").string()) << "esc\n* " << escape << "\n0 0 0\n0 0 0 1\n1\nsphere\n0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n.\n";
  load.path = (dir / "escape.scene").string();
  EXPECT_NE(call<LoadScene>("load_scene", load).response.error.find("escape.scene:2: object id 'crate\\x1B[2J' holds a control character"),
            std::string::npos);
  EXPECT_EQ(answers(), from_scene);

  // A malformed file: refused by file, line and field; nothing changed.
  std::ofstream((dir / "bad.scene").string()) << "bad\n* thing\n0 0 0\n0 0 0 1\n1\nsphere\n-1\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n.\n";
  load.path = (dir / "bad.scene").string();
  const std::string refused = call<LoadScene>("load_scene", load).response.error;
  EXPECT_NE(refused.find(load.path + ":7: object 'thing' shape 1 (sphere) radius is not a positive number"), std::string::npos) << refused;
  load.path = (dir / "missing.scene").string();
  EXPECT_NE(call<LoadScene>("load_scene", load).response.error.find("no such file"), std::string::npos);
  EXPECT_EQ(answers(), from_scene);

  // Merged: a new object joins the others; replaced (no merge): only it is left.
  std::ofstream((dir / "extra.scene").string()) << "extra\n* extra\n1\nbox\n0.1 0.1 0.1\n0 0.9 0.4\n0 0 0 1\n0 0 0 0\n.\n";
  load.path = (dir / "extra.scene").string();
  load.merge = true;
  ASSERT_EQ(call<LoadScene>("load_scene", load).response.error, "");
  CastRay::Request ray;
  ray.origin.x = 0.0, ray.origin.y = 1.5, ray.origin.z = 0.4;
  ray.direction.y = -1.0;
  EXPECT_EQ(call<CastRay>("cast_ray", ray).response.body, "extra");
  ray.origin.x = 1.5, ray.origin.y = 0.0, ray.origin.z = 0.5, ray.direction.x = -1.0, ray.direction.y = 0.0;
  EXPECT_EQ(call<CastRay>("cast_ray", ray).response.body, "post#0");
  load.merge = false;
  ASSERT_EQ(call<LoadScene>("load_scene", load).response.error, "");
  const CastRay::Response after = call<CastRay>("cast_ray", ray).response;
  EXPECT_TRUE(!after.hit || after.body.rfind("post", 0) != 0) << after.body;

  // A PlanningScene in YAML with its object in the camera's frame: placed through tf2 (the
  // camera at (1.5, -0.5, 0.8)); its robot state and matrix are not applied, and it says so.
  std::ofstream((dir / "camera.yaml").string())
      << "name: seen by the camera\n"
      << "robot_state: {joint_state: {name: [joint1], position: [0.5]}}\n"
      << "world:\n  collision_objects:\n    - id: crate\n      header: {frame_id: camera}\n"
      << "      primitives: [{type: 1, dimensions: [0.2, 0.2, 0.2]}]\n"
      << "      primitive_poses: [{position: {x: -1.0, y: 1.5, z: -0.3}, orientation: {x: 0, y: 0, z: 0, w: 1}}]\n"
      << "allowed_collision_matrix: {entry_names: [crate, hand], entry_values: [{enabled: [false, true]}, {enabled: [true, false]}]}\n";
  load.path = (dir / "camera.yaml").string();
  const LoadScene::Response yaml = call<LoadScene>("load_scene", load).response;
  ASSERT_EQ(yaml.error, "");
  EXPECT_EQ(yaml.name, "seen by the camera");
  EXPECT_NE(yaml.warning.find("its robot state is not applied (1 joints"), std::string::npos) << yaml.warning;
  EXPECT_EQ(yaml.warning.find("allowed-collision"), std::string::npos) << "(crate, hand) names an object: applied; " << yaml.warning;
  ray.origin.x = 0.5, ray.origin.y = 2.0, ray.origin.z = 0.5, ray.direction.x = 0.0, ray.direction.y = -1.0;
  const CastRay::Response crate = call<CastRay>("cast_ray", ray).response;
  EXPECT_EQ(crate.body, "crate");
  EXPECT_NEAR(crate.distance, 2.0 - 1.1, 1e-9) << "the crate's near face at y = 1.1 in the world";
  fs::remove_all(dir);
}

// Allowed collisions with objects, MoveIt's way: an object's default entry lets every link touch
// it (all its shapes), a pair entry wins over the default, removing entries checks it again;
// check_state names the allowed pairs that touch when asked. Bad requests change nothing.
TEST_F(NodeEnvironment, AllowedCollisionsLetLinksTouchAnObject) {
  std_srvs::Empty empty;
  ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
  SetCollisionObject::Request wrapper = box_object("wrapper", Vec3(0.3, 0.3, 0.3), Vec3(0.0, 0.0, 0.6));
  wrapper.primitives.push_back(wrapper.primitives[0]);  // two shapes: wrapper#0, wrapper#1
  wrapper.primitive_poses.push_back(wrapper.primitive_poses[0]);
  wrapper.primitive_poses[1].position.z += 0.1;
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", wrapper).response.error, "");
  const auto home = arm(0.0, 0.0);
  const CheckState::Response hit = check(home, 20);
  ASSERT_FALSE(hit.valid);
  ASSERT_FALSE(hit.contacts.empty());
  const std::string toucher = hit.contacts[0].body_a;
  auto set = [&](std::vector<std::string> a, std::vector<std::string> b, std::vector<std::string> defaults, bool allowed, bool remove) {
    SetAllowedCollisions::Request r;
    r.names_a = std::move(a), r.names_b = std::move(b), r.default_names = std::move(defaults);
    r.allowed = allowed, r.remove = remove;
    return call<SetAllowedCollisions>("set_allowed_collisions", r).response;
  };
  ASSERT_EQ(set({}, {}, {"wrapper"}, true, false).error, "");
  CheckState::Request ask = state_request(checker(), home);
  ask.report_allowed = true;
  const CheckState::Response allowed = call<CheckState>("check_state", ask).response;
  EXPECT_TRUE(allowed.valid) << "every link may touch the wrapper";
  ASSERT_EQ(allowed.allowed_links.size(), allowed.allowed_objects.size());
  ASSERT_FALSE(allowed.allowed_links.empty());
  EXPECT_NE(std::find(allowed.allowed_links.begin(), allowed.allowed_links.end(), toucher), allowed.allowed_links.end());
  for (const std::string& o : allowed.allowed_objects) {
    EXPECT_EQ(o, "wrapper") << "the object by its name, not its shapes'";
  }
  // A pair entry wins over the default: that link is checked against it again.
  ASSERT_EQ(set({toucher}, {"wrapper"}, {}, false, false).error, "");
  const CheckState::Response entry = check(home, 20);
  EXPECT_FALSE(entry.valid);
  for (const auto& c : entry.contacts) {
    EXPECT_EQ(c.body_a, toucher) << "only the link whose entry says so";
  }
  // Bad requests are refused by name and change nothing.
  EXPECT_NE(set({"link1"}, {"hand"}, {}, true, false).error.find("names two links"), std::string::npos);
  EXPECT_NE(set({"link1", "hand"}, {"wrapper"}, {}, true, false).error.find("2 names_a but 1 names_b"), std::string::npos);
  EXPECT_NE(set({}, {}, {"wrapper#0"}, true, false).error.find("contains '#' (it names an object's shapes"), std::string::npos);
  EXPECT_NE(set({"hand"}, {std::string("wrap\x1bper")}, {}, true, false).error.find("holds a control character"), std::string::npos);
  EXPECT_FALSE(check(home).valid);
  // A name known neither as a link nor as an object is kept, with a warning.
  const SetAllowedCollisions::Response later = set({"hand"}, {"not_yet"}, {}, true, false);
  EXPECT_EQ(later.error, "");
  EXPECT_NE(later.warning.find("'not_yet'"), std::string::npos) << later.warning;
  // Removed: back to no entries, the wrapper collides.
  ASSERT_EQ(set({toucher, "hand"}, {"wrapper", "not_yet"}, {"wrapper"}, false, true).error, "");
  const CheckState::Response again = call<CheckState>("check_state", ask).response;
  EXPECT_FALSE(again.valid);
  EXPECT_TRUE(again.allowed_links.empty());
  ASSERT_EQ(call<RemoveCollisionObject>("remove_collision_object", [] {
              RemoveCollisionObject::Request r;
              r.id = "wrapper";
              return r;
            }()).response.error, "");
}


// An object the hand carries (attach_object, detach_object): taken off the world where it is,
// moved with the hand in state checks, motions and rays, allowed to touch the fingers, put back
// where the hand holds it. The demo arm stands straight up (no joint_states: the neutral state),
// the hand's frame at z = 1.25 m; the parcel sits on the fingers, 9-17 cm above the hand frame.
TEST_F(NodeEnvironment, AttachedObjectMovesWithTheHand) {
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", box_object("parcel", Vec3(0.08, 0.08, 0.08), Vec3(0.0, 0.0, 1.38))).response.error, "");
  // A wall beside the parcel, above the hand and fingers: only the parcel can reach it.
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", box_object("wall", Vec3(0.02, 0.3, 0.14), Vec3(0.07, 0.0, 1.43))).response.error, "");
  const auto home = arm(0.0, 0.0);
  std::vector<double> tilted = home;
  tilted[4] = 0.2;  // joint5: the parcel swings 4-5 cm towards the wall, the hand 2 cm
  const CheckState::Response before = check(home, 10);
  ASSERT_FALSE(before.valid) << "the parcel sits on the fingers";
  for (const auto& c : before.contacts) {
    EXPECT_EQ(c.body_b, "parcel");
  }
  auto attach = [&](const std::string& id, const std::string& link, std::vector<std::string> touch) {
    AttachObject::Request r;
    r.id = id, r.link = link, r.touch_links = std::move(touch);
    return call<AttachObject>("attach_object", r).response.error;
  };
  auto detach = [&](const std::string& id, bool remove) {
    DetachObject::Request r;
    r.id = id, r.remove = remove;
    return call<DetachObject>("detach_object", r).response.error;
  };
  // Bad requests are refused by name and change nothing.
  EXPECT_NE(attach("parcel", "no_link", {}).find("no link 'no_link'"), std::string::npos);
  EXPECT_NE(attach("parcel", "hand", {"no_finger"}).find("'no_finger'"), std::string::npos);
  EXPECT_NE(attach("ghost", "hand", {}).find("no collision object 'ghost'"), std::string::npos);
  EXPECT_NE(attach("link3", "hand", {}).find("link's name"), std::string::npos);
  EXPECT_NE(detach("parcel", false).find("no attached object 'parcel'"), std::string::npos);
  EXPECT_NE(attach(std::string("par\x1b") + "cel", "hand", {}).find("id 'par\\x1Bcel' holds a control character"), std::string::npos);
  EXPECT_NE(detach(std::string("par") + '\0' + "cel", false).find("holds a control character (0x00 at byte 3)"), std::string::npos);
  EXPECT_FALSE(check(home).valid);
  ASSERT_EQ(attach("parcel", "hand", {"finger_left", "finger_right"}), "");
  EXPECT_NE(call<SetCollisionObject>("set_collision_object", box_object("parcel", Vec3(0.1, 0.1, 0.1), Vec3(1.0, 1.0, 1.0))).response.error.find("attached"),
            std::string::npos);
  EXPECT_TRUE(check(home).valid) << "carried: the fingers may touch it, and it left the world";
  const CheckState::Response swung = check(tilted, 10);
  ASSERT_FALSE(swung.valid) << "tilted, the carried parcel meets the wall";
  ASSERT_FALSE(swung.contacts.empty());
  for (const auto& c : swung.contacts) {
    EXPECT_EQ(c.body_a, "parcel");
    EXPECT_EQ(c.body_b, "wall");
  }
  CheckMotion::Request motion;
  for (const std::string& name : checker().model().variable_names()) motion.joint_names.push_back(name);
  motion.start = home, motion.goal = tilted;
  const CheckMotion::Response moved = call<CheckMotion>("check_motion", motion).response;
  EXPECT_EQ(moved.error, "");
  EXPECT_FALSE(moved.valid) << "the certified motion carries the parcel into the wall";
  EXPECT_GT(moved.last_valid_fraction, 0.0);
  // Answered at once without proxies; the same once the parcel's proxy levels are built.
  EXPECT_EQ(wait_for_diagnostic("attached objects' proxy levels", [](const std::string& v) { return v == "built"; }, 60.0), "built");
  EXPECT_EQ(check(tilted, 10).contacts.size(), swung.contacts.size());
  const CheckMotion::Response with_levels = call<CheckMotion>("check_motion", motion).response;
  EXPECT_FALSE(with_levels.valid);
  EXPECT_NEAR(with_levels.last_valid_fraction, moved.last_valid_fraction, 2e-3);  // (earliest to 1e-3)
  CastRay::Request ray;
  ray.origin.z = 2.0, ray.direction.z = -1.0;
  const CastRay::Response down = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(down.hit);
  EXPECT_EQ(down.body, "parcel");
  EXPECT_NEAR(down.point.z, 1.42, 1e-6);
  // Detached: back in the world where the hand holds it (at home, where it was taken from).
  ASSERT_EQ(detach("parcel", false), "");
  EXPECT_EQ(call<CastRay>("cast_ray", ray).response.body, "parcel");
  EXPECT_FALSE(check(home).valid) << "the fingers touch it in the world again";
  // Attached with its geometry in the hand's frame, then removed altogether.
  AttachObject::Request made;
  made.id = "cup", made.link = "hand";
  made.primitives = {solid(shape_msgs::SolidPrimitive::CYLINDER, {0.1, 0.03})};
  made.primitive_poses = {pose_at(Vec3(0.0, 0.0, 0.3))};
  made.pose.orientation.w = 1.0;
  ASSERT_EQ(call<AttachObject>("attach_object", made).response.error, "");
  ray.origin.x = 0.0, ray.origin.y = 0.0;
  const CastRay::Response cup = call<CastRay>("cast_ray", ray).response;
  EXPECT_EQ(cup.body, "cup");
  EXPECT_NEAR(cup.point.z, 1.25 + 0.35, 1e-6);
  ASSERT_EQ(detach("cup", true), "");
  EXPECT_EQ(call<CastRay>("cast_ray", ray).response.body, "parcel");
}

}  // namespace
}  // namespace bvh_collision::test
