// OMPL through the node (ros/service_validity.h): panda's straight motion from start to goal
// runs through a box the node knows only from a camera's point cloud; RRTConnect, asking the
// node's check_state and certified check_motion, finds a way around; every segment of the path is
// certified free by check_motion, its waypoints are free in one check_states call, and the
// straight motion is reported colliding.
#include <gtest/gtest.h>

#include <ompl/base/ScopedState.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "bvh_collision/ros/conversions.h"
#include "bvh_collision/CheckMotions.h"
#include "bvh_collision/CheckState.h"
#include "bvh_collision/PinWorld.h"
#include "bvh_collision/ros/service_validity.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

const Vec3 kCamera(1.5, 0.0, 1.0);  // the camera's origin in panda_link0 (translation only)
const std::vector<double> kStart = {-0.8, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785};
const std::vector<double> kGoal = {0.8, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785};

// The surface of an axis-aligned cube (edge `edge`, centre `centre` in panda_link0) every 1 cm,
// in the camera's frame.
std::vector<ScanPoint> cube_cloud(const Vec3& centre, double edge) {
  std::vector<ScanPoint> points;
  const int n = static_cast<int>(std::ceil(edge / 0.01));
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-0.5, 0.5}) {
      for (int i = 0; i <= n; ++i) {
        for (int j = 0; j <= n; ++j) {
          Vec3 p = centre;
          p[axis] += side * edge;
          p[(axis + 1) % 3] += (double(i) / n - 0.5) * edge;
          p[(axis + 2) % 3] += (double(j) / n - 0.5) * edge;
          points.push_back((p - kCamera).cast<float>());
        }
      }
    }
  }
  return points;
}

TEST(NodePlanning, RrtConnectThroughTheServicesAroundAnObstacleSeenOnlyAsACloud) {
  ros::NodeHandle nh, pnh("~");
  ASSERT_TRUE(wait_for_node());
  const CollisionChecker checker = library_checker(pnh.param<std::string>("urdf_file", ""));
  const RobotModel& model = checker.model();
  const planning::JointGroup arm = planning::JointGroup::of(
      model, {"panda_joint1", "panda_joint2", "panda_joint3", "panda_joint4", "panda_joint5", "panda_joint6", "panda_joint7"});

  // The robot holds the start; the cube sits where the hand passes halfway along the straight motion.
  std::vector<double> full(model.variable_count(), 0.0), middle = full;
  for (std::size_t i = 0; i < arm.size(); ++i) {
    const int v = int(std::find(model.variable_names().begin(), model.variable_names().end(), arm.names[i]) -
                      model.variable_names().begin());
    full[v] = kStart[i];
    middle[v] = 0.5 * (kStart[i] + kGoal[i]);
  }
  std::vector<Transform> poses;
  forward_kinematics(model, middle.data(), poses);
  const Vec3 cube_centre = poses[model.link_index("panda_hand")].t;

  ros::Publisher joints = nh.advertise<sensor_msgs::JointState>("joint_states", 10);
  ros::Publisher clouds = nh.advertise<sensor_msgs::PointCloud2>("obstacle_cloud", 1);
  tf2_ros::StaticTransformBroadcaster camera_tf;
  geometry_msgs::TransformStamped camera;
  camera.header.stamp = ros::Time::now();
  camera.header.frame_id = "panda_link0";
  camera.child_frame_id = "camera";
  camera.transform.translation.x = kCamera.x(), camera.transform.translation.y = kCamera.y();
  camera.transform.translation.z = kCamera.z(), camera.transform.rotation.w = 1.0;
  camera_tf.sendTransform(camera);
  const std::vector<ScanPoint> cloud_points = cube_cloud(cube_centre, 0.12);
  ros::WallTimer publisher = nh.createWallTimer(ros::WallDuration(0.05), [&](const ros::WallTimerEvent&) {
    const sensor_msgs::JointState js = joint_state(model.variable_names(), full);
    joints.publish(js);
    static int tick = 0;
    if (tick++ % 4 == 0) {
      sensor_msgs::PointCloud2 cloud = to_cloud_msg(cloud_points, "camera");
      cloud.header.stamp = js.header.stamp;
      clouds.publish(cloud);
    }
  });

  auto service = std::make_shared<ServicePlanningContext>("/collision_checker", arm);
  // The straight motion collides once the cube is in the node's octree (a cloud or two).
  double straight_fraction = 1.0;
  bool straight_free = true;
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);  // an event's deadline
  while (straight_free && ros::WallTime::now() < deadline) {
    service->new_plan();  // each poll asks the latest world (a plan pins one)
    straight_free = service->motion_valid(kStart.data(), kGoal.data(), &straight_fraction);
    if (straight_free) ros::WallDuration(0.1).sleep();
  }
  ASSERT_FALSE(straight_free) << "the straight motion through the cube is reported colliding";
  EXPECT_GT(straight_fraction, 0.1);
  EXPECT_LT(straight_fraction, 0.6);
  ASSERT_TRUE(service->state_valid(kStart.data()));
  ASSERT_TRUE(service->state_valid(kGoal.data()));

  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  ompl::RNG::setSeed(7);
  og::SimpleSetup setup(arm.make_space());
  setup.setStateValidityChecker(std::make_shared<ServiceStateValidityChecker>(setup.getSpaceInformation(), service));
  setup.getSpaceInformation()->setMotionValidator(std::make_shared<ServiceMotionValidator>(setup.getSpaceInformation(), service));
  ob::ScopedState<> start(setup.getStateSpace()), goal(setup.getStateSpace());
  for (std::size_t i = 0; i < arm.size(); ++i) start[i] = kStart[i], goal[i] = kGoal[i];
  setup.setStartAndGoalStates(start, goal);
  setup.setPlanner(std::make_shared<og::RRTConnect>(setup.getSpaceInformation()));
  // Bounded by work, not time: a seeded RRTConnect checks the same states on any machine.
  const auto checks = [&] { return service->counters->states.load() + service->counters->motions.load(); };
  const std::uint64_t before = checks();
  ASSERT_EQ(setup.solve(ob::PlannerTerminationCondition([&] { return checks() - before > 20000; })),
            ob::PlannerStatus::EXACT_SOLUTION);
  planning::simplify_or_keep(setup);  // a result the simplifier rejects is not kept
  EXPECT_GT(service->counters->states.load() + service->counters->motions.load(), 2u);

  const og::PathGeometric& path = setup.getSolutionPath();
  ASSERT_GE(path.getStateCount(), 3u);
  std::vector<double> waypoints;
  for (std::size_t w = 0; w < path.getStateCount(); ++w) {
    const double* v = path.getState(w)->as<ob::RealVectorStateSpace::StateType>()->values;
    waypoints.insert(waypoints.end(), v, v + arm.size());
    if (w + 1 == path.getStateCount()) break;
    const double* next = path.getState(w + 1)->as<ob::RealVectorStateSpace::StateType>()->values;
    EXPECT_TRUE(service->motion_valid(v, next)) << "segment " << w << " is certified free";
  }
  for (const bool free : service->states_valid(waypoints.data(), path.getStateCount())) {
    EXPECT_TRUE(free);
  }
  // One world for the plan (issue 58): every call above, the re-checks too, was answered by the
  // version the last poll pinned (the context throws otherwise), while the clouds that kept
  // arriving made newer ones; that version's snapshot does not change under it (PinnedVersions).
  const std::uint64_t pinned = service->world_version();
  EXPECT_NE(pinned, 0u);
  const ros::WallTime newer_deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  std::uint64_t latest = pinned;
  while (latest == pinned && ros::WallTime::now() < newer_deadline) {
    CheckState now;
    now.request.state.name = arm.names;
    now.request.state.position = kStart;
    ASSERT_TRUE(ros::service::call("/collision_checker/check_state", now));
    latest = now.response.world_version;
    if (latest == pinned) ros::WallDuration(0.1).sleep();
  }
  EXPECT_GT(latest, pinned) << "clouds made newer worlds while the plan held its own";
  EXPECT_TRUE(service->motion_valid(waypoints.data(), waypoints.data() + arm.size()));
  EXPECT_EQ(service->world_version(), pinned);
  PinWorld expired;  // a version never pinned is refused, naming the setting
  expired.request.release = true;
  expired.request.version = 987654321;
  ASSERT_TRUE(ros::service::call("/collision_checker/pin_world", expired));
  EXPECT_NE(expired.response.error.find("not pinned"), std::string::npos);
  CheckState stale;
  stale.request.state.name = arm.names;
  stale.request.state.position = kStart;
  stale.request.world_version = 987654321;
  ASSERT_TRUE(ros::service::call("/collision_checker/check_state", stale));
  EXPECT_NE(stale.response.error.find("pin_timeout"), std::string::npos) << stale.response.error;

  // check_motions: every segment and the straight motion in one call, each answered as
  // check_motion answers it (free segments; the straight motion colliding, free up to the same
  // fraction on the same octree: the clouds stop first).
  publisher.stop();
  std::vector<double> starts(waypoints.begin(), waypoints.end() - static_cast<std::ptrdiff_t>(arm.size()));
  std::vector<double> goals(waypoints.begin() + static_cast<std::ptrdiff_t>(arm.size()), waypoints.end());
  starts.insert(starts.end(), kStart.begin(), kStart.end());
  goals.insert(goals.end(), kGoal.begin(), kGoal.end());
  const std::size_t motions = path.getStateCount();
  std::vector<double> fractions;
  const std::vector<bool> free = service->motions_valid(starts.data(), goals.data(), motions, &fractions);
  ASSERT_EQ(free.size(), motions);
  for (std::size_t w = 0; w + 1 < motions; ++w) {
    EXPECT_TRUE(free[w]) << "segment " << w;
  }
  EXPECT_FALSE(free.back());
  double single = -1.0;
  EXPECT_FALSE(service->motion_valid(kStart.data(), kGoal.data(), &single));
  EXPECT_EQ(fractions.back(), single);
  // A request whose rows do not fit its joint names is refused by name, nothing answered.
  CheckMotions bad;
  bad.request.joint_names = arm.names;
  bad.request.starts.assign(arm.size() + 1, 0.0);
  bad.request.goals.assign(arm.size() + 1, 0.0);
  ASSERT_TRUE(ros::service::call("/collision_checker/check_motions", bad));
  EXPECT_NE(bad.response.error.find("whole number of rows"), std::string::npos) << bad.response.error;
  EXPECT_TRUE(bad.response.valid.empty());
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_planning"); }
