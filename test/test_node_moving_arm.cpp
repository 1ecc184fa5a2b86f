// Launch test (issue 19, point 1): the demo arm sweeps joint1 at 1.5 rad/s past a camera whose
// clouds show the arm where it was at their stamp and arrive 100 ms late. The self filter must
// place the arm at each cloud's stamp: after 50 clouds no occupied voxel lies on the arm at any
// of those poses (with the latest joint state instead, the arm's own points 0.15 rad behind stay
// as obstacles it then collides with: this test failed so, at nearly every pose), and a real
// obstacle 3 cm below the arm's path is kept.
#include <atomic>
#include <deque>
#include <mutex>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <geometry_msgs/TransformStamped.h>
#include <ros/topic.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include "bvh_collision/CastRay.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

constexpr double kSpeed = 1.5;                    // rad/s of joint1
constexpr double kLate = 0.1;                     // s between a cloud's stamp and its delivery
const Vec3 kCamera(1.2, 0.0, 1.2);                // in base_link; the camera frame is only shifted
const Vec3 kObstacleSize(0.08, 0.08, 0.04);       // a block below the arm's path
constexpr double kObstacleX = 0.5;

// joint1 sweeps -1 .. 1 rad and back at kSpeed; joint2 leans the arm out at 1 rad.
std::vector<double> arm_at(const CollisionChecker& checker, double t) {
  const double period = 4.0 / kSpeed;
  const double phase = std::fmod(t, period) / period;  // 0 .. 1
  const double q1 = phase < 0.5 ? -1.0 + 4.0 * phase : 3.0 - 4.0 * phase;
  std::vector<double> q(checker.model().variable_count(), 0.0);
  const auto& names = checker.model().variable_names();
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == "joint1") q[i] = q1;
    if (names[i] == "joint2") q[i] = 1.0;
  }
  return q;
}

// The block's centre height that puts its top 3 cm below the arm's path (the smallest distance
// over the sweep, by the library's exact distance), found by bisection.
double obstacle_height(const CollisionChecker& checker) {
  double lo = 0.0, hi = 0.8;
  for (int i = 0; i < 30; ++i) {
    const double z = 0.5 * (lo + hi);
    Environment env(0.02);
    env.add_object("block", ObjectShape::box(kObstacleSize), Transform::Translation(Vec3(kObstacleX, 0.0, z)));
    double nearest = 1e9;
    for (int k = 0; k <= 100; ++k) {
      EnvironmentRequest r;
      r.distance = true;
      r.octree = false;
      const std::vector<double> q = arm_at(checker, (4.0 / kSpeed) * k / 100.0);
      nearest = std::min(nearest, checker.check_environment(q.data(), env, r).min_distance);
    }
    (nearest > 0.03 ? lo : hi) = z;
  }
  return lo;
}

// A depth camera at kCamera looking at the arm: the first hit of each ray on the arm (the
// library's own ray cast) or on the block; points in the camera frame.
std::vector<ScanPoint> render(const CollisionChecker& checker, const std::vector<double>& q, double block_z) {
  const Environment nothing(0.02);
  const Vec3 lo = Vec3(kObstacleX, 0.0, block_z) - 0.5 * kObstacleSize, hi = lo + kObstacleSize;
  const Vec3 forward = (Vec3(0.35, 0.0, 0.45) - kCamera).normalized(), right = Vec3(0, -1, 0);
  const Vec3 up = right.cross(forward) * -1.0;
  std::vector<ScanPoint> points;
  for (int v = 0; v < 60; ++v) {
    for (int u = 0; u < 80; ++u) {
      const Vec3 d = (forward + std::tan(0.7) * (2.0 * (u + 0.5) / 80 - 1.0) * right +
                      std::tan(0.55) * (2.0 * (v + 0.5) / 60 - 1.0) * up).normalized();
      double best = 5.0;
      const RayCastResult arm = checker.cast_ray(q.data(), nothing, kCamera, d, best);
      if (arm.hit) best = arm.distance;
      double t0 = 0.0, t1 = best;  // the block: slabs
      for (int a = 0; a < 3 && t0 <= t1; ++a) {
        const double s1 = (lo[a] - kCamera[a]) / d[a], s2 = (hi[a] - kCamera[a]) / d[a];
        t0 = std::max(t0, std::min(s1, s2));
        t1 = std::min(t1, std::max(s1, s2));
      }
      if (t0 <= t1) best = t0;
      if (best < 5.0) points.push_back((d * best).cast<float>());  // camera frame: base_link shifted
    }
  }
  return points;
}

TEST(NodeMovingArm, CloudsMeetTheArmWhereItWasAtTheirStamp) {
  std::string urdf;
  ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
  const CollisionChecker checker = library_checker(urdf);
  ASSERT_TRUE(wait_for_node());
  const double block_z = obstacle_height(checker);

  ros::NodeHandle nh;
  tf2_ros::StaticTransformBroadcaster static_tf;
  geometry_msgs::TransformStamped camera;
  camera.header.frame_id = "base_link";
  camera.child_frame_id = "camera";
  camera.header.stamp = ros::Time::now();
  camera.transform.translation.x = kCamera.x();
  camera.transform.translation.z = kCamera.z();
  camera.transform.rotation.w = 1.0;
  static_tf.sendTransform(camera);
  ros::Publisher joints = nh.advertise<sensor_msgs::JointState>("joint_states", 100);
  ros::Publisher clouds = nh.advertise<sensor_msgs::PointCloud2>("obstacle_cloud", 10);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while ((joints.getNumSubscribers() == 0 || clouds.getNumSubscribers() == 0) && ros::WallTime::now() < deadline) {
    ros::WallDuration(0.05).sleep();  // every cloud sent must reach the node to be counted
  }
  ASSERT_GT(clouds.getNumSubscribers(), 0u);

  const ros::Time start = ros::Time::now();
  std::vector<double> stamps;                                  // seconds after start
  std::deque<std::pair<ros::Time, sensor_msgs::PointCloud2>> in_flight;
  ros::Time next_cloud = start;
  ros::Rate rate(100.0);
  while (stamps.size() < 50 || !in_flight.empty()) {
    const ros::Time now = ros::Time::now();
    const double t = (now - start).toSec();
    sensor_msgs::JointState js = joint_state(checker.model().variable_names(), arm_at(checker, t));
    js.header.stamp = now;
    joints.publish(js);
    if (stamps.size() < 50 && now >= next_cloud) {
      sensor_msgs::PointCloud2 cloud = to_cloud_msg(render(checker, arm_at(checker, t), block_z), "camera");
      cloud.header.stamp = now;
      in_flight.emplace_back(now + ros::Duration(kLate), cloud);
      stamps.push_back(t);
      next_cloud = now + ros::Duration(0.1);
    }
    while (!in_flight.empty() && in_flight.front().first <= now) {
      clouds.publish(in_flight.front().second);
      in_flight.pop_front();
    }
    rate.sleep();
  }
  // Park the arm away from the block, then let the last cloud land.
  std::vector<double> parked = arm_at(checker, 0.0);
  for (std::size_t i = 0; i < parked.size(); ++i) {
    if (checker.model().variable_names()[i] == "joint1") parked[i] = -2.5;
  }
  // The robot keeps publishing its (parked) state, as a real one does: cast_ray below takes it.
  std::atomic<bool> parked_done{false};
  std::thread parked_publisher([&] {
    while (!parked_done) {
      sensor_msgs::JointState js = joint_state(checker.model().variable_names(), parked);
      js.header.stamp = ros::Time::now();
      joints.publish(js);
      ros::Duration(0.02).sleep();
    }
  });
  struct Join {
    std::atomic<bool>& done;
    std::thread& thread;
    ~Join() { done = true, thread.join(); }
  } join{parked_done, parked_publisher};
  // Every cloud is accounted for: inserted, or superseded by a newer one while the node was busy
  // (a busy machine supersedes more, and inserts fewer); none lacked the arm's state at its
  // stamp, none its transform.
  const CloudCounts counts = wait_for_clouds(stamps.size());
  EXPECT_GT(counts.inserted, 0u);
  EXPECT_EQ(counts.inserted + counts.superseded, stamps.size());
  EXPECT_EQ(counts.no_state, 0u);
  EXPECT_EQ(counts.no_transform, 0u);
  RecordProperty("clouds_inserted", std::to_string(counts.inserted));

  // No voxel on the arm at any pose a cloud saw it in.
  int colliding = 0;
  for (const double t : stamps) {
    auto request = state_request(checker, arm_at(checker, t), CheckState::Request::ENVIRONMENT);
    request.max_contacts = 5;
    const auto r = call<CheckState>("check_state", request).response;
    ASSERT_EQ(r.error, "");
    if (r.environment_collision) {
      ++colliding;
      ADD_FAILURE() << "at t = " << t << " the arm meets a voxel at (" << r.contacts.front().position.x << ", "
                    << r.contacts.front().position.y << ", " << r.contacts.front().position.z << ")";
    }
  }
  EXPECT_EQ(colliding, 0);

  // The block 3 cm below the path is still there: a ray down onto its top (the arm parked away)
  // meets the voxels of its top face.
  CastRay::Request ray;
  ray.origin.x = kObstacleX;
  ray.origin.z = 1.0;
  ray.direction.z = -1.0;
  const auto hit = call<CastRay>("cast_ray", ray).response;
  ASSERT_EQ(hit.error, "");
  ASSERT_TRUE(hit.hit);
  EXPECT_EQ(hit.body, "octree");
  const double top = block_z + 0.5 * kObstacleSize.z();
  EXPECT_GE(hit.point.z, top - 1e-6);
  EXPECT_LE(hit.point.z, top + 0.02 + 1e-6);  // the voxel holding the top face

  // A cloud from before the history (10 s), and one stamped past the newest joint state by more
  // than joint_state_lead plus the wait for states to come (~cloud_transform_timeout, 2 s here):
  // the robot's pose then is unknown, so both are dropped and counted. Each is sent once the one
  // before has its outcome, so neither supersedes the other.
  std::uint64_t sent = counts.sent();
  for (const double offset : {-20.0, 20.0}) {
    sensor_msgs::PointCloud2 cloud = to_cloud_msg(render(checker, parked, block_z), "camera");
    cloud.header.stamp = ros::Time::now() + ros::Duration(offset);
    clouds.publish(cloud);
    wait_for_clouds(++sent);
  }
  EXPECT_EQ(cloud_counts().no_state, 2u);
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_moving_arm"); }
