// Launch test: a world that changes (issue 36). Two nodes on the demo arm take the same clouds:
// /collision_checker with ~clear_no_return (a CameraInfo topic gives NaN pixels their rays) and
// /octomap_rule without it (OctoMap's insertPointCloud). The test plays the robot's driver
// (joint_states, tf) and the cameras:
// - a depth camera sees a box that is then taken away, leaving nothing in range (every pixel NaN);
// - an overhead camera sees a table and a box that a planner moves across it as a collision object;
// - a camera on a sweeping mount sees a pillar, each cloud stamped before the latest transform.
#include <algorithm>
#include <condition_variable>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <unistd.h>

#include "bvh_collision/CastRay.h"
#include "bvh_collision/RemoveCollisionObject.h"
#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

constexpr const char* kNoReturn = "/collision_checker";
constexpr const char* kOctomapRule = "/octomap_rule";
constexpr double kFx = 40.0, kFy = 40.0, kCx = 31.5, kCy = 23.5;
constexpr std::uint32_t kWidth = 64, kHeight = 48;
const float kNan = std::numeric_limits<float>::quiet_NaN();

geometry_msgs::TransformStamped transform_msg(const std::string& parent, const std::string& child, const Transform& x,
                                              const ros::Time& stamp) {
  geometry_msgs::TransformStamped m;
  m.header.stamp = stamp;
  m.header.frame_id = parent;
  m.child_frame_id = child;
  m.transform.translation.x = x.t.x(), m.transform.translation.y = x.t.y(), m.transform.translation.z = x.t.z();
  const Eigen::Quaterniond q(x.R);
  m.transform.rotation.x = q.x(), m.transform.rotation.y = q.y(), m.transform.rotation.z = q.z(), m.transform.rotation.w = q.w();
  return m;
}

Transform pose(const Vec3& t, const Mat3& R) {
  Transform x;
  x.R = R;
  x.t = t;
  return x;
}

Mat3 columns(const Vec3& x, const Vec3& y, const Vec3& z) {
  Mat3 R;
  R << x, y, z;
  return R;
}

// Where a ray from `o` along `d` enters the axis-aligned box [lo, hi] (slabs), or infinity.
double box_entry(const Vec3& o, const Vec3& d, const Vec3& lo, const Vec3& hi) {
  double a = 0.0, b = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (o[i] < lo[i] || o[i] > hi[i]) return std::numeric_limits<double>::infinity();
      continue;
    }
    const double t1 = (lo[i] - o[i]) / d[i], t2 = (hi[i] - o[i]) / d[i];
    a = std::max(a, std::min(t1, t2));
    b = std::min(b, std::max(t1, t2));
  }
  return a <= b ? a : std::numeric_limits<double>::infinity();
}

struct Box {
  Vec3 lo, hi;
};

// A depth image's organized cloud in the camera's optical frame: each pixel's ray meets the
// nearest box within 2.5 m, else returns nothing (NaN).
sensor_msgs::PointCloud2 depth_cloud(const Transform& camera, const std::vector<Box>& boxes, const std::string& frame) {
  std::vector<ScanPoint> points;
  for (std::uint32_t v = 0; v < kHeight; ++v) {
    for (std::uint32_t u = 0; u < kWidth; ++u) {
      const Vec3 ray((u - kCx) / kFx, (v - kCy) / kFy, 1.0);  // z = 1: the entry parameter is the depth
      double depth = 2.5;
      for (const Box& b : boxes) depth = std::min(depth, box_entry(camera.t, camera.R * ray, b.lo, b.hi));
      points.push_back(depth < 2.5 ? (ray * depth).cast<float>() : ScanPoint(kNan, kNan, kNan));
    }
  }
  sensor_msgs::PointCloud2 cloud = to_cloud_msg(points, frame);
  cloud.height = kHeight;
  cloud.width = kWidth;
  cloud.row_step = kWidth * cloud.point_step;
  cloud.is_dense = false;
  return cloud;
}

// The robot's driver: joint states at 50 Hz (the arm upright), the base where the world is.
class Driver {
 public:
  explicit Driver(const std::vector<std::string>& names)
      : pub_(nh_.advertise<sensor_msgs::JointState>("/joint_states", 10)),
        state_(joint_state(names, std::vector<double>(names.size(), 0.0))),
        timer_(nh_.createWallTimer(ros::WallDuration(0.02), &Driver::tick, this)) {}

 private:
  void tick(const ros::WallTimerEvent&) {
    state_.header.stamp = ros::Time::now();
    pub_.publish(state_);
  }
  ros::NodeHandle nh_;
  ros::Publisher pub_;
  sensor_msgs::JointState state_;
  ros::WallTimer timer_;
};

// Clouds inserted by each node, from every diagnostics message (a subscriber kept for the whole
// suite: each new one would wait for a connection and the next message).
class InsertedClouds {
 public:
  InsertedClouds()
      : sub_(ros::NodeHandle().subscribe<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10, &InsertedClouds::on, this)) {}
  // Waits (a deadline of 60 s for the event) until every node has inserted `count`; what each has.
  std::map<std::string, std::uint64_t> wait(std::uint64_t count, const std::vector<std::string>& nodes) {
    std::unique_lock<std::mutex> lock(mutex_);
    grew_.wait_for(lock, std::chrono::seconds(60), [&] {
      return std::all_of(nodes.begin(), nodes.end(), [&](const std::string& n) { return inserted_[n] >= count; });
    });
    return inserted_;
  }

 private:
  void on(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& status : msg->status) {
      const std::string node = status.name.substr(0, status.name.find(':'));
      for (const auto& kv : status.values) {
        if (kv.key == "clouds inserted") inserted_[node] = std::stoull(kv.value);
      }
    }
    grew_.notify_all();
  }
  std::mutex mutex_;
  std::condition_variable grew_;
  std::map<std::string, std::uint64_t> inserted_;
  ros::Subscriber sub_;
};

// The centres of the occupied voxels of a node's octree (saved and read back).
std::vector<Vec3> occupied(const std::string& node) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("changing_world_" + std::to_string(::getpid()) + ".bt")).string();
  SaveOctree::Request save;
  save.path = path;
  EXPECT_EQ(call_on<SaveOctree>(node, "save_octree", save).response.error, "");
  const Octree tree = load_octree(path);
  std::filesystem::remove(path);
  std::vector<Vec3> out;
  for (const Octree::Leaf& leaf : tree.leaves()) {
    if (tree.occupied(leaf.log_odds)) out.push_back(tree.cube_min(leaf.key) + Vec3::Constant(0.5 * tree.cube_size(leaf.depth)));
  }
  return out;
}

int count_in(const std::vector<Vec3>& centres, const Vec3& lo, const Vec3& hi) {
  int n = 0;
  for (const Vec3& c : centres) n += (c.array() >= lo.array()).all() && (c.array() <= hi.array()).all();
  return n;
}

class NodeChangingWorld : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string urdf;
    ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
    const CollisionChecker checker = library_checker(urdf);
    driver_ = new Driver(checker.model().variable_names());
    inserted_ = new InsertedClouds();
    statics_ = new tf2_ros::StaticTransformBroadcaster();
    statics_->sendTransform(transform_msg("world", "base_link", Transform::Identity(), ros::Time::now()));
    ASSERT_TRUE(wait_for_node(kNoReturn));
    ASSERT_TRUE(wait_for_node(kOctomapRule));
    joint_states_from(kNoReturn);
    joint_states_from(kOctomapRule);
  }
  // Publishes the cloud and waits until both nodes have inserted it.
  void show(const sensor_msgs::PointCloud2& cloud) {
    static ros::Publisher pub = ros::NodeHandle().advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1);
    while (pub.getNumSubscribers() < 2) ros::WallDuration(0.01).sleep();
    pub.publish(cloud);
    ++sent_;
    const auto inserted = inserted_->wait(sent_, {kNoReturn, kOctomapRule});
    for (const char* node : {kNoReturn, kOctomapRule}) EXPECT_EQ(inserted.at(node), sent_) << node;
  }
  // Every cloud sent was inserted, none dropped or rejected (the waits above only see insertions).
  static void TearDownTestSuite() {
    for (const char* node : {kNoReturn, kOctomapRule}) {
      const CloudCounts c = wait_for_clouds(sent_, 60.0, node);
      EXPECT_EQ(c.inserted, sent_) << node;
    }
  }
  static Driver* driver_;
  static InsertedClouds* inserted_;
  static tf2_ros::StaticTransformBroadcaster* statics_;
  static std::uint64_t sent_;
};
Driver* NodeChangingWorld::driver_ = nullptr;
InsertedClouds* NodeChangingWorld::inserted_ = nullptr;
tf2_ros::StaticTransformBroadcaster* NodeChangingWorld::statics_ = nullptr;
std::uint64_t NodeChangingWorld::sent_ = 0;

// A box seen three times, then taken away: nothing is left in range, every pixel is NaN. With
// ~clear_no_return the dark pixels' rays clear it within the scans the sensor model needs (3 hits
// at log-odds 0.85 take 7 misses of -0.41); by OctoMap's rule nothing ever clears it.
TEST_F(NodeChangingWorld, DarkPixelsClearWhatWasThere) {
  // The depth camera at x = 2 looking back along -x (optical z forward, y down).
  const Transform camera = pose({2.0, 0.0, 0.5}, columns({0, 1, 0}, {0, 0, -1}, {-1, 0, 0}));
  statics_->sendTransform(transform_msg("world", "depth_optical", camera, ros::Time::now()));
  ros::NodeHandle nh;
  ros::Publisher info = nh.advertise<sensor_msgs::CameraInfo>("/depth/camera_info", 1, true);
  sensor_msgs::CameraInfo k;
  k.header.frame_id = "depth_optical";
  k.width = kWidth, k.height = kHeight;
  k.K = {kFx, 0, kCx, 0, kFy, kCy, 0, 0, 1};
  info.publish(k);
  while (info.getNumSubscribers() < 1) ros::WallDuration(0.01).sleep();
  const Box box{{1.1, -0.2, 0.3}, {1.3, 0.2, 0.7}};
  const Vec3 lo = box.lo - Vec3::Constant(0.03), hi = box.hi + Vec3::Constant(0.03);
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::PointCloud2 cloud = depth_cloud(camera, {box}, "depth_optical");
    cloud.header.stamp = ros::Time::now();
    show(cloud);
  }
  ASSERT_GT(count_in(occupied(kNoReturn), lo, hi), 50);
  ASSERT_EQ(count_in(occupied(kNoReturn), lo, hi), count_in(occupied(kOctomapRule), lo, hi));
  int scans = 0;
  for (; scans < 12 && count_in(occupied(kNoReturn), lo, hi) > 0; ++scans) {
    sensor_msgs::PointCloud2 cloud = depth_cloud(camera, {}, "depth_optical");
    cloud.header.stamp = ros::Time::now();
    show(cloud);
  }
  EXPECT_EQ(count_in(occupied(kNoReturn), lo, hi), 0) << "after " << scans << " scans with no return";
  EXPECT_EQ(scans, 7) << "the sensor model's count: 3 hits (2.54) need 7 misses (-0.41 each) to fall below 0";
  EXPECT_GT(count_in(occupied(kOctomapRule), lo, hi), 50) << "by OctoMap's rule a ray with no return clears nothing";
  EXPECT_GE(std::stoull(diagnostic("rays with no return cast", kNoReturn)), std::uint64_t(scans) * kWidth * kHeight);
  EXPECT_EQ(diagnostic("pixels with no return and no camera model", kNoReturn), "0");
}

// The same without a CameraInfo (a depth camera as most are configured): the node fits the
// camera to its clouds and keeps the fit for the clouds that hold too little to fit, such as one
// in which every pixel is NaN.
TEST_F(NodeChangingWorld, WithoutCameraInfoTheFittedCameraClears) {
  const Transform camera = pose({2.0, 0.7, 0.5}, columns({0, 1, 0}, {0, 0, -1}, {-1, 0, 0}));
  statics_->sendTransform(transform_msg("world", "unlisted_optical", camera, ros::Time::now()));
  const Box box{{1.1, 0.5, 0.3}, {1.3, 0.9, 0.7}};
  const Vec3 lo = box.lo - Vec3::Constant(0.03), hi = box.hi + Vec3::Constant(0.03);
  for (int i = 0; i < 3; ++i) {
    sensor_msgs::PointCloud2 cloud = depth_cloud(camera, {box}, "unlisted_optical");
    cloud.header.stamp = ros::Time::now();
    show(cloud);
  }
  ASSERT_GT(count_in(occupied(kNoReturn), lo, hi), 50);
  for (int scans = 0; scans < 7; ++scans) {
    sensor_msgs::PointCloud2 cloud = depth_cloud(camera, {}, "unlisted_optical");
    cloud.header.stamp = ros::Time::now();
    show(cloud);
  }
  EXPECT_EQ(count_in(occupied(kNoReturn), lo, hi), 0) << "the fitted camera's rays clear the box in 7 scans";
  EXPECT_GT(count_in(occupied(kOctomapRule), lo, hi), 50);
  EXPECT_EQ(diagnostic("pixels with no return and no camera model", kNoReturn), "0");
}

// A box that a planner moves across a table as a collision object, seen from above after each
// move: its points are never voxels, so it leaves nothing behind, and the table stays. A second
// box that no one told the node about is a voxel obstacle, as it should be.
TEST_F(NodeChangingWorld, AMovedObjectLeavesNoVoxels) {
  const Transform camera = pose({0.9, 0.9, 1.5}, columns({1, 0, 0}, {0, -1, 0}, {0, 0, -1}));
  statics_->sendTransform(transform_msg("world", "overhead_optical", camera, ros::Time::now()));
  const Box table{{0.5, 0.5, 0.3}, {1.3, 1.3, 0.4}}, unknown{{1.1, 0.55, 0.4}, {1.2, 0.65, 0.5}};
  const Vec3 size(0.1, 0.1, 0.1);
  std::vector<Vec3> centres;
  for (int step = 0; step <= 5; ++step) {
    const Vec3 c(0.6 + 0.08 * step, 0.7 + 0.08 * step, 0.45);
    centres.push_back(c);
    ASSERT_EQ(call_on<SetCollisionObject>(kNoReturn, "set_collision_object", box_object("moved", size, c)).response.error, "");
    ASSERT_EQ(call_on<SetCollisionObject>(kOctomapRule, "set_collision_object", box_object("moved", size, c)).response.error, "");
    sensor_msgs::PointCloud2 cloud = depth_cloud(camera, {table, unknown, {c - size / 2, c + size / 2}}, "overhead_optical");
    cloud.header.stamp = ros::Time::now();
    show(cloud);
  }
  RemoveCollisionObject::Request remove;
  remove.id = "moved";
  for (const char* node : {kNoReturn, kOctomapRule}) {
    ASSERT_EQ(call_on<RemoveCollisionObject>(node, "remove_collision_object", remove).response.error, "");
    const std::vector<Vec3> cells = occupied(node);
    for (const Vec3& c : centres) {
      EXPECT_EQ(count_in(cells, c - Vec3(0.06, 0.06, 0.02), c + Vec3(0.06, 0.06, 0.07)), 0) << node << " at " << c.transpose();
    }
    EXPECT_GT(count_in(cells, unknown.lo - Vec3::Constant(0.02), unknown.hi + Vec3::Constant(0.02)), 5) << node;
    EXPECT_GT(count_in(cells, Vec3(0.5, 0.5, 0.36), Vec3(1.3, 1.3, 0.42)), 500) << node << ": the table stays";
    EXPECT_GE(std::stoull(diagnostic("points on known objects", node)), 6u * 8u) << node;
  }
}

// A camera on a mount that sweeps (as on the arm: tf gives its pose at every instant): each cloud
// is stamped 0.15 s before the newest transform, when the camera looked 0.15 rad elsewhere (a
// pillar 1 m away would land 15 cm off). Inserted at the pose of its stamp, every voxel is on the
// pillar: no ghosts.
TEST_F(NodeChangingWorld, ASweepingCameraLeavesNoGhosts) {
  tf2_ros::TransformBroadcaster tf;
  const ros::Time t0 = ros::Time::now();
  const Vec3 mount(-0.8, -0.9, 0.6);
  auto camera_at = [&](const ros::Time& t) {  // looking along +y, yawing at 1 rad/s through +-0.4 rad
    const double yaw = 0.4 * std::sin((t - t0).toSec() / 0.4);
    return pose(mount, Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix());
  };
  std::mutex mutex;
  bool sweeping = true;
  std::thread mover([&] {
    for (;;) {
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (!sweeping) return;
      }
      const ros::Time now = ros::Time::now();
      tf.sendTransform(transform_msg("world", "arm_camera", camera_at(now), now));
      ros::WallDuration(0.005).sleep();
    }
  });
  const Vec3 lo(-0.9, 0.15, 0.2), hi(-0.7, 0.25, 1.0);  // the pillar
  // (Transforms sent before the nodes' tf listeners connect to this broadcaster are lost: the
  // first cloud's stamp must come after the connection, a deadline for that event.)
  ros::WallDuration(1.0).sleep();
  for (int k = 0; k < 8; ++k) {
    ros::WallDuration(0.2).sleep();
    const ros::Time stamp = ros::Time::now() - ros::Duration(0.15);
    const Transform at = camera_at(stamp);
    std::vector<ScanPoint> points;  // the pillar's face towards the camera, in the camera's frame then
    for (double x = lo.x(); x <= hi.x(); x += 0.01) {
      for (double z = lo.z(); z <= hi.z(); z += 0.01) points.push_back((at.inverse() * Vec3(x, lo.y(), z)).cast<float>());
    }
    sensor_msgs::PointCloud2 cloud = to_cloud_msg(points, "arm_camera");
    cloud.header.stamp = stamp;
    show(cloud);
  }
  {
    std::lock_guard<std::mutex> lock(mutex);
    sweeping = false;
  }
  mover.join();
  for (const char* node : {kNoReturn, kOctomapRule}) {
    const std::vector<Vec3> cells = occupied(node);
    const Vec3 near_lo(-1.5, -0.5, 0.0), near_hi(-0.3, 1.0, 1.3);  // around the pillar, away from the robot and the other tests
    const int on_pillar = count_in(cells, lo - Vec3::Constant(0.02), hi + Vec3::Constant(0.02));
    EXPECT_GT(on_pillar, 50) << node;
    EXPECT_EQ(count_in(cells, near_lo, near_hi), on_pillar) << node << ": voxels off the pillar (ghosts)";
  }
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_changing_world"); }
