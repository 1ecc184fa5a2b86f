// Pick and place on panda through the node's services, as a MoveIt user does it: a box on a
// table; the fingers allowed to touch it (set_allowed_collisions); attached to the hand
// (attach_object) at the grasp; carried over a fence that only the box can hit (check_state names
// the box as the body; the certified motion is colliding, without the box it is free); the self
// filter drops the carried box's points from a camera cloud (the saved octree holds none there);
// OMPL plans around the fence through the node's services with the box in hand; placed on a second
// table (detach_object), where it stays. The test publishes joint_states: the robot "moves".
#include <gtest/gtest.h>

#include <atomic>
#include <filesystem>
#include <mutex>

#include <ompl/base/ScopedState.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "bvh_collision/AttachObject.h"
#include "bvh_collision/CastRay.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/DetachObject.h"
#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/SetAllowedCollisions.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/ros/conversions.h"
#include "bvh_collision/ros/service_validity.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

const std::vector<std::string> kArm = {"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4",
                                       "panda_joint5", "panda_joint6", "panda_joint7"};
const std::vector<std::string> kFingers = {"panda_leftfinger", "panda_rightfinger"};
const Vec3 kBoxSize(0.04, 0.04, 0.06);
constexpr double kGrip = 0.11;  // the box's centre below the hand frame's origin (along the hand's z)
const Vec3 kCamera(0.3, -1.2, 0.6);  // in panda_link0 (translation only)

// panda's ready pose turned about the base by `j1`: the hand points down.
std::vector<double> ready(const CollisionChecker& c, double j1) {
  std::vector<double> q(c.model().variable_count(), 0.0);
  const std::vector<double> arm = {j1, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
  for (std::size_t i = 0; i < kArm.size(); ++i) {
    const auto& names = c.model().variable_names();
    q[std::find(names.begin(), names.end(), kArm[i]) - names.begin()] = arm[i];
  }
  const auto& names = c.model().variable_names();
  q[std::find(names.begin(), names.end(), "panda_finger_joint1") - names.begin()] = 0.02;  // the box's width apart
  return q;
}

Transform hand_at(const CollisionChecker& c, const std::vector<double>& q) {
  std::vector<Transform> poses;
  forward_kinematics(c.model(), q.data(), poses);
  return poses[c.model().link_index("panda_hand")];
}

template <class Service>
std::string error_of(const std::string& service, const typename Service::Request& request) {
  return call<Service>(service, request).response.error;
}

// The points of a box's surface every 1 cm, in the camera's frame.
std::vector<ScanPoint> box_points(const Transform& pose, const Vec3& size) {
  std::vector<ScanPoint> out;
  for (const Vec3& p : box_surface(pose, size)) out.push_back((p - kCamera).cast<float>());
  return out;
}

// Publishes joint_states (the robot's current state) and, when set, a camera cloud.
class FakeRobot {
 public:
  FakeRobot(const CollisionChecker& c, std::vector<double> q) : checker_(c), q_(std::move(q)) {
    joints_ = nh_.advertise<sensor_msgs::JointState>("joint_states", 10);
    clouds_ = nh_.advertise<sensor_msgs::PointCloud2>("obstacle_cloud", 1);
    timer_ = nh_.createWallTimer(ros::WallDuration(0.05), [this](const ros::WallTimerEvent&) { tick(); });
  }
  // A tick that the spinner runs while the test's scope ends must not publish on a topic being
  // unadvertised (a clean-clone run aborted there, in roscpp's TopicManager::publish, after the
  // test had passed): the timer stopped and the ticks told to stop before the publishers go.
  ~FakeRobot() {
    timer_.stop();
    std::lock_guard<std::mutex> lock(mutex_);
    stopped_ = true;
  }
  FakeRobot(const FakeRobot&) = delete;
  FakeRobot& operator=(const FakeRobot&) = delete;
  void move_to(const std::vector<double>& q) {
    std::lock_guard<std::mutex> lock(mutex_);
    q_ = q;
  }
  void show(std::vector<ScanPoint> points) {
    std::lock_guard<std::mutex> lock(mutex_);
    cloud_ = std::move(points);
  }
  std::uint64_t clouds_sent() const { return sent_.load(); }

 private:
  void tick() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopped_) return;
    const sensor_msgs::JointState js = joint_state(checker_.model().variable_names(), q_);
    joints_.publish(js);
    if (!cloud_.empty() && tick_++ % 4 == 0) {
      sensor_msgs::PointCloud2 cloud = to_cloud_msg(cloud_, "camera");
      cloud.header.stamp = js.header.stamp;
      clouds_.publish(cloud);
      ++sent_;
    }
  }
  const CollisionChecker& checker_;
  ros::NodeHandle nh_;
  ros::Publisher joints_, clouds_;
  std::mutex mutex_;
  std::vector<double> q_;
  std::vector<ScanPoint> cloud_;
  int tick_ = 0;
  bool stopped_ = false;
  std::atomic<std::uint64_t> sent_{0};
  ros::WallTimer timer_;
};

// Waits (a generous deadline: an event) until a ray along the hand's x axis (at these states,
// from outside towards the base), through where the box sits between the fingers when the hand
// is at `hand`, meets the box's face there: the node has the hand there with the box on it (or
// the box was left there).
testing::AssertionResult box_seen_at(const Transform& hand) {
  const Vec3 centre = hand * Vec3(0.0, 0.0, kGrip), along = hand.R.col(0);
  const Vec3 origin = centre + 0.5 * along, face = centre + 0.5 * kBoxSize.x() * along;
  CastRay::Request ray;
  ray.origin.x = origin.x(), ray.origin.y = origin.y(), ray.origin.z = origin.z();
  ray.direction.x = -along.x(), ray.direction.y = -along.y(), ray.direction.z = -along.z();
  CastRay::Response r;
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0); ros::WallTime::now() < end;) {
    r = call<CastRay>("cast_ray", ray).response;
    if (r.hit && r.body == "box" && (Vec3(r.point.x, r.point.y, r.point.z) - face).norm() < 1e-3) return testing::AssertionSuccess();
    ros::WallDuration(0.05).sleep();
  }
  return testing::AssertionFailure() << "the ray meets '" << r.body << "' at (" << r.point.x << ", " << r.point.y << ", "
                                     << r.point.z << "), the box's face is at (" << face.transpose() << ")" << r.error;
}

TEST(NodePickPlace, PickCarryOverAFenceAndPlace) {
  ros::NodeHandle pnh("~");
  ASSERT_TRUE(wait_for_node());
  const CollisionChecker checker = library_checker(pnh.param<std::string>("urdf_file", ""));
  const std::vector<double> grasp = ready(checker, -0.7), over = ready(checker, 0.0), place = ready(checker, 0.7);
  const Transform hand_grasp = hand_at(checker, grasp), hand_over = hand_at(checker, over), hand_place = hand_at(checker, place);
  // The box between the fingers at the grasp, its long side along the hand's z (pointing down).
  const Transform box_pose{hand_grasp.R, hand_grasp * Vec3(0.0, 0.0, kGrip)};
  const double bottom = box_pose.t.z() - 0.5 * kBoxSize.z();
  const double place_bottom = (hand_place * Vec3(0.0, 0.0, kGrip)).z() - 0.5 * kBoxSize.z();
  // A fence under the hand's way: its top 1.5 cm above the box's lowest point and about as far
  // below the fingertips (checked below with the library).
  const double fence_top = (hand_over * Vec3(0.0, 0.0, kGrip)).z() - 0.5 * kBoxSize.z() + 0.015;
  const Vec3 fence_at(hand_over.t.x(), hand_over.t.y(), 0.5 * fence_top);
  auto table = [](const std::string& id, const Vec3& under, double top) {
    return box_object(id, Vec3(0.15, 0.15, 0.02), Vec3(under.x(), under.y(), top - 0.01));
  };
  FakeRobot robot(checker, grasp);
  joint_states_from();
  tf2_ros::StaticTransformBroadcaster camera_tf;
  geometry_msgs::TransformStamped camera;
  camera.header.stamp = ros::Time::now();
  camera.header.frame_id = "panda_link0", camera.child_frame_id = "camera";
  camera.transform.translation.x = kCamera.x(), camera.transform.translation.y = kCamera.y(), camera.transform.translation.z = kCamera.z();
  camera.transform.rotation.w = 1.0;
  camera_tf.sendTransform(camera);

  SetCollisionObject::Request box = box_object("box", kBoxSize, box_pose.t);
  box.pose.orientation = to_pose_msg(box_pose).orientation;
  ASSERT_EQ(error_of<SetCollisionObject>("set_collision_object", box), "");
  ASSERT_EQ(error_of<SetCollisionObject>("set_collision_object", table("table", box_pose.t, bottom - 0.002)), "");
  ASSERT_EQ(error_of<SetCollisionObject>("set_collision_object", table("table2", hand_place.t, place_bottom - 0.002)), "");
  // The fence: across the hand's way at its middle (the way is a circle about the base's z axis).
  SetCollisionObject::Request fence = box_object("fence", Vec3(0.2, 0.02, fence_top), fence_at);
  ASSERT_EQ(error_of<SetCollisionObject>("set_collision_object", fence), "");

  // The library's answers on the same scene first: the fence is in the box's way, not the arm's.
  auto env = std::make_shared<Environment>(0.02);
  env->add_object("table", ObjectShape::box(Vec3(0.15, 0.15, 0.02)), Transform::Translation(Vec3(box_pose.t.x(), box_pose.t.y(), bottom - 0.012)));
  env->add_object("fence", ObjectShape::box(Vec3(0.2, 0.02, fence_top)), Transform::Translation(fence_at));
  ASSERT_FALSE(SceneChecker(checker, env).collides(over.data())) << "the arm alone passes over the fence";
  ASSERT_TRUE(SceneChecker(checker, env).check_motion(grasp.data(), place.data()).valid);

  // Approach: the fingers touch the box until allowed to.
  const CheckState::Response touching = call<CheckState>("check_state", [&] {
    CheckState::Request r = state_request(checker, grasp);
    r.max_contacts = 10;
    return r;
  }()).response;
  ASSERT_FALSE(touching.valid) << "the fingers hold the box";
  for (const auto& c : touching.contacts) {
    EXPECT_EQ(c.body_b, "box");
  }
  SetAllowedCollisions::Request allow;
  allow.names_a = kFingers, allow.names_b = {"box", "box"}, allow.allowed = true;
  ASSERT_EQ(error_of<SetAllowedCollisions>("set_allowed_collisions", allow), "");
  EXPECT_TRUE(call<CheckState>("check_state", state_request(checker, grasp)).response.valid);

  // Attach where it is (the node reads the grasp from joint_states).
  AttachObject::Request attach;
  attach.id = "box", attach.link = "panda_hand", attach.touch_links = kFingers;
  ASSERT_EQ(error_of<AttachObject>("attach_object", attach), "");
  ASSERT_TRUE(box_seen_at(hand_grasp));
  EXPECT_TRUE(call<CheckState>("check_state", state_request(checker, grasp)).response.valid);

  // Over the fence with the box in hand: the box, and only it, hits the fence.
  CheckState::Request at_fence = state_request(checker, over);
  at_fence.max_contacts = 10;
  const CheckState::Response hit = call<CheckState>("check_state", at_fence).response;
  ASSERT_FALSE(hit.valid);
  ASSERT_FALSE(hit.contacts.empty());
  for (const auto& c : hit.contacts) {
    EXPECT_EQ(c.body_a, "box");
    EXPECT_EQ(c.body_b, "fence");
  }
  CheckMotion::Request straight;
  straight.joint_names = checker.model().variable_names();
  straight.start = grasp, straight.goal = place;
  const CheckMotion::Response carried = call<CheckMotion>("check_motion", straight).response;
  EXPECT_EQ(carried.error, "");
  EXPECT_FALSE(carried.valid) << "the certified motion carries the box into the fence";
  EXPECT_GT(carried.last_valid_fraction, 0.2);
  EXPECT_LT(carried.last_valid_fraction, 0.5);

  // The self filter: the camera sees the carried box and a cube beyond the robot; only the cube
  // reaches the octree.
  const Vec3 cube_at(-0.4, -0.6, 0.3);
  std::vector<ScanPoint> points = box_points(box_pose, kBoxSize), cube = box_points(Transform::Translation(cube_at), Vec3(0.1, 0.1, 0.1));
  points.insert(points.end(), cube.begin(), cube.end());
  robot.show(points);
  while (robot.clouds_sent() < 4) ros::WallDuration(0.05).sleep();
  robot.show({});
  wait_for_clouds(robot.clouds_sent());
  const std::string saved = (std::filesystem::temp_directory_path() / ("pick_place_" + std::to_string(::getpid()) + ".bt")).string();
  SaveOctree::Request save;
  save.path = saved;
  ASSERT_EQ(call<SaveOctree>("save_octree", save).response.error, "");
  const Octree tree = load_octree(saved);
  std::filesystem::remove(saved);
  int near_cube = 0, near_box = 0;
  for (const Octree::Leaf& leaf : tree.leaves()) {
    if (!tree.occupied(leaf.log_odds)) continue;
    const Vec3 c = tree.cube_min(leaf.key) + Vec3::Constant(0.5 * tree.cube_size(leaf.depth));
    near_cube += (c - cube_at).norm() < 0.15;
    near_box += (c - box_pose.t).norm() < 0.1;
  }
  EXPECT_GT(near_cube, 10) << "the cube's points are obstacles";
  EXPECT_EQ(near_box, 0) << "the carried box's points are not";

  // OMPL plans around the fence through the node, the box in hand.
  const planning::JointGroup arm = planning::JointGroup::of(checker.model(), kArm);
  auto service = std::make_shared<ServicePlanningContext>("/collision_checker", arm);
  auto group_values = [&](const std::vector<double>& q) {
    std::vector<double> v;
    for (const std::string& name : kArm) {
      const auto& names = checker.model().variable_names();
      v.push_back(q[std::find(names.begin(), names.end(), name) - names.begin()]);
    }
    return v;
  };
  const std::vector<double> from = group_values(grasp), to = group_values(place);
  ASSERT_FALSE(service->motion_valid(from.data(), to.data()));
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  ompl::RNG::setSeed(11);
  og::SimpleSetup setup(arm.make_space());
  setup.setStateValidityChecker(std::make_shared<ServiceStateValidityChecker>(setup.getSpaceInformation(), service));
  setup.getSpaceInformation()->setMotionValidator(std::make_shared<ServiceMotionValidator>(setup.getSpaceInformation(), service));
  ob::ScopedState<> start(setup.getStateSpace()), goal(setup.getStateSpace());
  for (std::size_t i = 0; i < arm.size(); ++i) start[i] = from[i], goal[i] = to[i];
  setup.setStartAndGoalStates(start, goal);
  setup.setPlanner(std::make_shared<og::RRTConnect>(setup.getSpaceInformation()));
  const auto checks = [&] { return service->counters->states.load() + service->counters->motions.load(); };
  const std::uint64_t before = checks();
  ASSERT_EQ(setup.solve(ob::PlannerTerminationCondition([&] { return checks() - before > 20000; })), ob::PlannerStatus::EXACT_SOLUTION);
  planning::simplify_or_keep(setup);  // a result the simplifier rejects is not kept
  const og::PathGeometric& path = setup.getSolutionPath();
  ASSERT_GE(path.getStateCount(), 3u) << "not the straight motion";
  // Every segment certified free with the box, by the node and by the library carrying the same box.
  Environment carrying = *env;
  AttachedBody held{"box", "panda_hand", kFingers, {make_collision_object("box", ObjectShape::box(kBoxSize), relative_transform(hand_grasp, box_pose))}};
  carrying.attach(held);
  const SceneChecker library(checker, std::make_shared<const Environment>(carrying));
  for (std::size_t w = 0; w + 1 < path.getStateCount(); ++w) {
    const double* a = path.getState(w)->as<ob::RealVectorStateSpace::StateType>()->values;
    const double* b = path.getState(w + 1)->as<ob::RealVectorStateSpace::StateType>()->values;
    EXPECT_TRUE(service->motion_valid(a, b)) << "segment " << w;
    std::vector<double> qa = grasp, qb = grasp;
    for (std::size_t i = 0; i < arm.size(); ++i) {
      const auto& names = checker.model().variable_names();
      const auto v = std::find(names.begin(), names.end(), kArm[i]) - names.begin();
      qa[v] = a[i], qb[v] = b[i];
    }
    EXPECT_TRUE(library.check_motion(qa.data(), qb.data()).valid) << "segment " << w << " by the library";
  }

  // Placed: the robot at the place state, the box detached into the world on the second table.
  robot.move_to(place);
  ASSERT_TRUE(box_seen_at(hand_place)) << "the node has the hand, and the box on it, at the place";
  DetachObject::Request detach;
  detach.id = "box";
  ASSERT_EQ(error_of<DetachObject>("detach_object", detach), "");
  EXPECT_NE(error_of<DetachObject>("detach_object", detach).find("no attached object"), std::string::npos);
  // The hand leaves (once the node has it back over the fence, a ray from above meets the arm
  // there); the box stays where it was placed, a world object the arm may hit again.
  robot.move_to(over);
  CastRay::Request above;
  above.origin.x = hand_over.t.x(), above.origin.y = hand_over.t.y(), above.origin.z = hand_over.t.z() + 1.0;
  above.direction.z = -1.0;
  bool left = false;
  for (const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(60.0); !left && ros::WallTime::now() < end;) {
    const CastRay::Response r = call<CastRay>("cast_ray", above).response;
    left = r.hit && r.body.rfind("panda_", 0) == 0;
    if (!left) ros::WallDuration(0.05).sleep();
  }
  ASSERT_TRUE(left);
  EXPECT_TRUE(box_seen_at(hand_place)) << "the box stays on the second table";
  const CheckState::Response back = call<CheckState>("check_state", state_request(checker, place)).response;
  EXPECT_TRUE(back.valid) << "at the place, the fingers may touch it (allowed), nothing else does";
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_pick_place"); }
