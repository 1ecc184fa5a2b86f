// Launch test: the node's environment through tf2, as a robot's drivers feed it. The node runs
// with world_frame "world"; this test is the robot's tf (world -> base_link, which it moves) and a
// camera (world -> camera, static) that publishes obstacle clouds in its own frame.
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

namespace bvh_collision::test {
namespace {

const Vec3 kCamera(1.5, -0.5, 0.8);  // the camera's origin in world (translation only)

geometry_msgs::TransformStamped translation(const std::string& parent, const std::string& child, const Vec3& t) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = ros::Time::now();
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = t.x();
  m.transform.translation.y = t.y();
  m.transform.translation.z = t.z();
  m.transform.rotation.w = 1.0;
  return m;
}

// The robot's base in world, broadcast at 50 Hz as a localisation would.
class BaseBroadcaster {
 public:
  BaseBroadcaster() : timer_(nh_.createWallTimer(ros::WallDuration(0.02), &BaseBroadcaster::tick, this)) {}
  void move_to(const Vec3& t) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      base_ = t;
    }
  }

 private:
  void tick(const ros::WallTimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    tf_.sendTransform(translation("world", "base_link", base_));
  }
  ros::NodeHandle nh_;
  tf2_ros::TransformBroadcaster tf_;
  std::mutex mutex_;
  Vec3 base_ = Vec3::Zero();
  ros::WallTimer timer_;
};

class NodeEnvironment : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    base_ = new BaseBroadcaster();
    camera_tf_ = new tf2_ros::StaticTransformBroadcaster();
    camera_tf_->sendTransform(translation("world", "camera", kCamera));
    std::string urdf;
    ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
    checker_ = new CollisionChecker(library_checker(urdf));
    ASSERT_TRUE(wait_for_node());
    // Before any test clears it: the node started with ~scene_file's box at (0, 1.2, 0.3).
    CastRay::Request ray;
    ray.origin.y = 2.0, ray.origin.z = 0.3;
    ray.direction.y = -1.0;
    // (Once the base's transform has reached the node: a deadline for that event.)
    for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0); ros::WallTime::now() < end;) {
      start_scene_hit_ = call<CastRay>("cast_ray", ray).response;
      if (start_scene_hit_.error.empty()) break;
      ros::WallDuration(0.05).sleep();
    }
  }
  void SetUp() override {
    std_srvs::Empty empty;
    ASSERT_TRUE(ros::service::call(node_service("clear_environment"), empty));
    base_->move_to(Vec3::Zero());
  }
  const CollisionChecker& checker() const { return *checker_; }
  std::vector<double> arm(double j1, double j2) const {
    std::vector<double> q(checker().model().variable_count(), 0.0);
    q[0] = j1;
    q[1] = j2;
    return q;
  }
  CheckState::Response check(const std::vector<double>& q, std::uint32_t max_contacts = 0) const {
    CheckState::Request r = state_request(checker(), q);
    r.max_contacts = max_contacts;
    return call<CheckState>("check_state", r).response;
  }

  static BaseBroadcaster* base_;
  static CastRay::Response start_scene_hit_;
  static tf2_ros::StaticTransformBroadcaster* camera_tf_;
  static CollisionChecker* checker_;
};
BaseBroadcaster* NodeEnvironment::base_ = nullptr;
CastRay::Response NodeEnvironment::start_scene_hit_;
tf2_ros::StaticTransformBroadcaster* NodeEnvironment::camera_tf_ = nullptr;
CollisionChecker* NodeEnvironment::checker_ = nullptr;

// A wall of points 1 cm apart at x = 0.55 (world), y in [-0.25, 0.25], z in [0.3, 1.0], expressed
// in the camera's frame.
sensor_msgs::PointCloud2 wall_cloud() {
  std::vector<ScanPoint> points;
  for (double y = -0.25; y <= 0.25; y += 0.01) {
    for (double z = 0.3; z <= 1.0; z += 0.01) points.push_back((Vec3(0.55, y, z) - kCamera).cast<float>());
  }
  return to_cloud_msg(points, "camera");
}

template <class Predicate>
bool eventually(Predicate p, double seconds = 60.0) {  // a deadline for an event, not a speed
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(seconds); ros::WallTime::now() < end;) {
    if (p()) return true;
    ros::WallDuration(0.05).sleep();
  }
  return p();
}

TEST_F(NodeEnvironment, CloudInACameraFrameCollidesAndClearBoxFreesIt) {
  const auto reach = arm(0.0, 1.0), home = arm(0.0, 0.0);
  // The first test after start-up: the node may still lack the base's tf for a moment (a CI run
  // answered invalid here once); what it says then is printed.
  CheckState::Response first;
  ASSERT_TRUE(eventually([&] { return (first = check(reach)).valid; }))
      << "nothing to hit yet, but: error '" << first.error << "', self " << first.self_collision << ", environment "
      << first.environment_collision;
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1, true);
  sensor_msgs::PointCloud2 cloud = wall_cloud();
  cloud.header.stamp = ros::Time::now();
  pub.publish(cloud);
  ASSERT_TRUE(eventually([&] { return !check(reach).valid; })) << "the cloud never made the reach collide";
  const CheckState::Response hit = check(reach, 5);
  EXPECT_TRUE(hit.environment_collision);
  EXPECT_FALSE(hit.self_collision);
  ASSERT_FALSE(hit.contacts.empty());
  for (const Contact& c : hit.contacts) {
    EXPECT_EQ(c.body_b, "octree");
    // Contacts are in world: at the wall, not where the wall is in the camera's frame.
    EXPECT_NEAR(c.position.x, 0.55, 0.1) << c.body_a;
  }
  EXPECT_TRUE(check(home).valid) << "the arm upright stays clear of the wall";

  ClearBox::Request box;
  box.min.x = 0.5, box.min.y = -0.3, box.min.z = 0.25;
  box.max.x = 0.6, box.max.y = 0.3, box.max.z = 1.05;
  EXPECT_EQ(call<ClearBox>("clear_box", box).response.error, "");
  EXPECT_TRUE(check(reach).valid) << "clear_box left the wall in place";
}

TEST_F(NodeEnvironment, MarkersAndDiagnosticsShowTheCloud) {
  ros::NodeHandle nh;
  std::mutex mutex;
  visualization_msgs::MarkerArray cells;
  std::map<std::string, std::string> values;
  ros::Subscriber cells_sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "/collision_checker/occupied_cells", 1, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        cells = *m;
      });
  ros::Subscriber diag_sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& status : m->status) {
          for (const auto& kv : status.values) values[kv.key] = kv.value;
        }
      });
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1, true);
  sensor_msgs::PointCloud2 cloud = wall_cloud();
  cloud.header.stamp = ros::Time::now();
  pub.publish(cloud);
  ASSERT_TRUE(eventually([&] { return !check(arm(0.0, 1.0)).valid; }));
  const auto cube_count = [&] {
    std::lock_guard<std::mutex> lock(mutex);
    std::size_t n = 0;
    for (const auto& m : cells.markers) {
      if (m.type == visualization_msgs::Marker::CUBE_LIST) n += m.points.size();
    }
    return n;
  };
  EXPECT_TRUE(eventually([&] { return cube_count() > 100; })) << cube_count() << " voxels drawn";
  const auto value = [&](const std::string& key) {
    std::lock_guard<std::mutex> lock(mutex);
    return values.count(key) ? std::stoll(values[key]) : -1LL;
  };
  EXPECT_TRUE(eventually([&] { return value("clouds inserted") >= 1; }));
  EXPECT_GE(value("clouds received"), 1);
  EXPECT_GT(value("points received"), 3000);
  EXPECT_GT(value("octree nodes"), 100);
  EXPECT_GT(value("octree memory (bytes)"), 0);
  EXPECT_TRUE(eventually([&] { return value("check_state requests") >= 1; }));
}

// rviz started after a colliding query still shows its contacts: the topic is latched and the
// node publishes contacts whether or not anyone listens at the time (rviz, started late, showed
// none).
TEST_F(NodeEnvironment, ContactsReachASubscriberThatComesLater) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1, true);
  sensor_msgs::PointCloud2 cloud = wall_cloud();
  cloud.header.stamp = ros::Time::now();
  pub.publish(cloud);
  ASSERT_TRUE(eventually([&] { return !check(arm(0.0, 1.0)).valid; }));
  ros::WallDuration(0.2).sleep();  // past the node's 10 Hz limit on contact markers
  const auto answer = check(arm(0.0, 1.0), 3);
  ASSERT_FALSE(answer.contacts.empty());
  std::mutex mutex;
  std::size_t spheres = 0;
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "/collision_checker/contacts", 1, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const auto& marker : m->markers) {
          if (marker.type == visualization_msgs::Marker::SPHERE_LIST) spheres = marker.points.size();
        }
      });
  EXPECT_TRUE(eventually([&] {
    std::lock_guard<std::mutex> lock(mutex);
    return spheres == answer.contacts.size();
  })) << spheres << " contact spheres received, " << answer.contacts.size() << " contacts answered";
}

TEST_F(NodeEnvironment, TheBasePoseComesFromTf) {
  SetCollisionObject::Request object = box_object("crate", Vec3(0.3, 0.3, 0.3), Vec3(2.0, 0.0, 0.6));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  const auto home = arm(0.0, 0.0);
  EXPECT_TRUE(check(home).valid);
  base_->move_to(Vec3(2.0, 0.0, 0.0));  // the crate is now where the arm stands, once tf says so
  ASSERT_TRUE(eventually([&] { return !check(home).valid; })) << "the node never took the base's new pose";
  const CheckState::Response moved = check(home, 1);
  EXPECT_FALSE(moved.valid);
  ASSERT_EQ(moved.contacts.size(), 1u);
  EXPECT_EQ(moved.contacts[0].body_b, "crate");
  EXPECT_NEAR(moved.contacts[0].position.x, 2.0, 0.2) << "contact not in world_frame";
  base_->move_to(Vec3(0.0, 0.0, 0.0));
  EXPECT_TRUE(eventually([&] { return check(home).valid; }));
  // An object given in another frame is placed through tf: (-1.5, 0.5, -0.2) from the camera is
  // (0, 0, 0.6) in world, onto the arm.
  object.frame_id = "camera";
  object.pose.position.x = -1.5;
  object.pose.position.y = 0.5;
  object.pose.position.z = -0.2;
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  EXPECT_FALSE(check(home).valid) << "an object given in the camera frame was not moved into world";
  RemoveCollisionObject::Request remove;
  remove.id = "crate";
  EXPECT_EQ(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
  EXPECT_TRUE(check(home).valid);
}

TEST_F(NodeEnvironment, CertifiedMotionFindsAThinObstacleThatACoarseStepMisses) {
  // A 2 mm plate in the plane y = 0 that the arm, leaning forward, sweeps through when joint1
  // turns from -0.75 to 0.85 rad.
  const auto plate = box_object("plate", Vec3(0.6, 0.002, 0.7), Vec3(0.6, 0.0, 0.65));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", plate).response.error, "");
  CheckMotion::Request motion;
  motion.joint_names = {"joint1", "joint2"};
  motion.start = {-0.75, 1.0};
  motion.goal = {0.85, 1.0};
  ASSERT_TRUE(check(arm(-0.75, 1.0)).valid);
  ASSERT_TRUE(check(arm(0.85, 1.0)).valid);
  ASSERT_FALSE(check(arm(0.0, 1.0)).valid) << "the plate must block the middle of the motion";

  // The library on the same scene: the coarse step misses the plate, the certified check does not.
  Environment env(0.02);
  env.add_object("plate", ObjectShape::box(Vec3(0.6, 0.002, 0.7)), Transform::Translation(Vec3(0.6, 0.0, 0.65)));
  const auto start = arm(-0.75, 1.0), goal = arm(0.85, 1.0);
  MotionRequest coarse_lib;
  coarse_lib.resolution = 0.7;
  ASSERT_TRUE(checker().check_motion(start.data(), goal.data(), env, coarse_lib).valid)
      << "the test's premise: a 0.7 rad step steps over the plate";

  motion.resolution = 0.7;
  const auto coarse = call<CheckMotion>("check_motion", motion).response;
  EXPECT_EQ(coarse.error, "");
  EXPECT_TRUE(coarse.valid) << "same answer as the library at resolution 0.7";
  EXPECT_EQ(coarse.states_checked, 4u);

  motion.resolution = 0.0;
  const auto certified = call<CheckMotion>("check_motion", motion).response;
  EXPECT_EQ(certified.error, "");
  EXPECT_FALSE(certified.valid) << "the certified check missed the plate";
  EXPECT_GT(certified.last_valid_fraction, 0.2);
  EXPECT_LT(certified.last_valid_fraction, 0.5) << "the plate is at joint1 = 0, fraction 0.47";
  // The node certifies through a SceneChecker (checker/scene_checker.h), which finds the first
  // collision to a thousandth of the motion; the library's general check_motion steps up to it.
  const MotionResult lib = checker().check_motion(start.data(), goal.data(), env, MotionRequest{});
  EXPECT_NEAR(certified.last_valid_fraction, lib.last_valid_fraction, 1e-3);
  EXPECT_LE(certified.last_valid_fraction, lib.colliding_fraction) << "free up to beyond a collision";
}

TEST_F(NodeEnvironment, CastRayHitsLinksObjectsAndVoxels) {
  CastRay::Request ray;
  ray.origin.x = 1.0;
  ray.origin.z = 0.5;
  ray.direction.x = -1.0;
  auto r = call<CastRay>("cast_ray", ray).response;
  EXPECT_EQ(r.error, "");
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body.rfind("link", 0), 0u) << "the upright arm is hit first, not " << r.body;
  EXPECT_NEAR(r.point.x, 0.05, 0.02);

  const auto ball = primitive_object("ball", solid(shape_msgs::SolidPrimitive::SPHERE, {0.1}), Vec3(0.6, 0.0, 0.5));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", ball).response.error, "");
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "ball");
  EXPECT_NEAR(r.distance, 0.3, 1e-6);
  ray.max_range = 0.2;
  EXPECT_FALSE(call<CastRay>("cast_ray", ray).response.hit) << "max_range ends the ray before the ball";
  RemoveCollisionObject::Request remove;
  remove.id = "ball";
  EXPECT_EQ(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
}

// A post at (0.6, 0, 0.5): a cone (height 0.4, base radius 0.1: radius 0.05 at mid height) over a
// box plinth below it.
SetCollisionObject::Request cone_on_plinth() {
  using shape_msgs::SolidPrimitive;
  SetCollisionObject::Request object;
  object.id = "post";
  object.pose = pose_at(Vec3(0.6, 0.0, 0.5));
  object.primitives = {solid(SolidPrimitive::CONE, {0.4, 0.1}), solid(SolidPrimitive::BOX, {0.3, 0.3, 0.1})};
  object.primitive_poses = {pose_at(Vec3::Zero()), pose_at(Vec3(0.0, 0.0, -0.25))};
  return object;
}

// shape_msgs as MoveIt's CollisionObject carries them: an object of several shapes, each at its
// own pose, its parts named id#k; a cone is exact (a ray meets its slanted side where the
// cone's radius puts it, not where a faceted cone would), and replacing or removing the object
// takes every part.
TEST_F(NodeEnvironment, ShapeMsgsObjectsWithExactConesAndSeveralShapes) {
  using shape_msgs::SolidPrimitive;
  SetCollisionObject::Request object = cone_on_plinth();
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  CastRay::Request ray;
  ray.origin.x = 1.0, ray.origin.y = 0.0, ray.origin.z = 0.5;
  ray.direction.x = -1.0;
  auto r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "post#0");
  EXPECT_NEAR(r.distance, 0.35, 1e-9) << "the cone's radius at mid height is exactly 0.05";
  ray.origin.z = 0.69;  // 1 cm below the tip: radius 0.0025
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_NEAR(r.distance, 0.4 - 0.0025, 1e-9);
  ray.origin.z = 0.25;  // the plinth
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "post#1");
  EXPECT_NEAR(r.distance, 0.25, 1e-9);

  // Replaced by one shape: no part of the old object stays behind.
  object.primitives = {solid(SolidPrimitive::CYLINDER, {0.4, 0.02})};
  object.primitive_poses = {pose_at(Vec3::Zero())};
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  r = call<CastRay>("cast_ray", ray).response;
  EXPECT_TRUE(!r.hit || r.body.rfind("post", 0) != 0) << "the plinth was replaced, hit " << r.body;
  ray.origin.z = 0.5;
  r = call<CastRay>("cast_ray", ray).response;
  ASSERT_TRUE(r.hit);
  EXPECT_EQ(r.body, "post");
  EXPECT_NEAR(r.distance, 0.38, 1e-9);

  // Two shapes again, then removed together by the object's id.
  object.primitives.push_back(solid(SolidPrimitive::SPHERE, {0.05}));
  object.primitive_poses.push_back(pose_at(Vec3(0.0, 0.0, -0.3)));
  ASSERT_EQ(call<SetCollisionObject>("set_collision_object", object).response.error, "");
  RemoveCollisionObject::Request remove;
  remove.id = "post";
  EXPECT_EQ(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
  for (const double z : {0.5, 0.2}) {
    ray.origin.z = z;
    r = call<CastRay>("cast_ray", ray).response;
    EXPECT_TRUE(!r.hit || r.body.rfind("post", 0) != 0) << "removed, still hit " << r.body << " at z " << z;
  }
  EXPECT_NE(call<RemoveCollisionObject>("remove_collision_object", remove).response.error, "");
}

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
  EXPECT_NE(yaml.warning.find("not applied: its robot state (1 joints"), std::string::npos) << yaml.warning;
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
  for (const std::string& o : allowed.allowed_objects) EXPECT_EQ(o, "wrapper") << "the object by its name, not its shapes'";
  // A pair entry wins over the default: that link is checked against it again.
  ASSERT_EQ(set({toucher}, {"wrapper"}, {}, false, false).error, "");
  const CheckState::Response entry = check(home, 20);
  EXPECT_FALSE(entry.valid);
  for (const auto& c : entry.contacts) EXPECT_EQ(c.body_a, toucher) << "only the link whose entry says so";
  // Bad requests are refused by name and change nothing.
  EXPECT_NE(set({"link1"}, {"hand"}, {}, true, false).error.find("names two links"), std::string::npos);
  EXPECT_NE(set({"link1", "hand"}, {"wrapper"}, {}, true, false).error.find("2 names_a but 1 names_b"), std::string::npos);
  EXPECT_NE(set({}, {}, {"wrapper#0"}, true, false).error.find("names a shape"), std::string::npos);
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
  for (const auto& c : before.contacts) EXPECT_EQ(c.body_b, "parcel");
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

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_node_environment");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);  // tf broadcasts and subscriptions run while tests wait
  spinner.start();
  return RUN_ALL_TESTS();
}
