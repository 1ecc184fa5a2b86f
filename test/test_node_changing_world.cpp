// Launch test: a world that changes (issue 36). Two nodes on the demo arm take the same clouds:
// /collision_checker with ~clear_no_return (a CameraInfo topic gives NaN pixels their rays) and
// /octomap_rule without it (OctoMap's insertPointCloud). The test plays the robot's driver
// (joint_states, tf) and the cameras:
// - a depth camera sees a box that is then taken away, leaving nothing in range (every pixel NaN);
// - an overhead camera sees a table and a box that a planner moves across it as a collision object;
// - a camera on the hand of the sweeping arm sees a pillar, each cloud stamped before the latest
//   joint state and transform.
#include <algorithm>
#include <cstdio>
#include <condition_variable>
#include <filesystem>
#include <functional>
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
#include "bvh_collision/robot/robot_model.h"
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

// The robot's driver: joint states at 100 Hz, following `motion` (joint values at a time; the
// arm upright until told), and what robot_state_publisher would add for a camera on the hand: its
// frame "hand_camera" in world at the same instants.
class Driver {
 public:
  using Motion = std::function<std::vector<double>(const ros::Time&)>;
  Driver(const std::vector<std::string>& names, CollisionChecker checker)
      : pub_(nh_.advertise<sensor_msgs::JointState>("/joint_states", 10)),
        names_(names),
        checker_(std::move(checker)),
        motion_([n = names.size()](const ros::Time&) { return std::vector<double>(n, 0.0); }),
        timer_(nh_.createWallTimer(ros::WallDuration(0.01), &Driver::tick, this)) {}
  void follow(Motion motion) {
    std::lock_guard<std::mutex> lock(mutex_);
    motion_ = std::move(motion);
  }
  // The hand camera in world with the arm at `q`: 5 cm out of the hand along its z, looking that way.
  Transform camera_at(const std::vector<double>& q) const {
    std::vector<Transform> poses;
    forward_kinematics(checker_.model(), q.data(), poses);
    return poses[checker_.model().link_index("hand")] * pose({0, 0, 0.05}, Mat3::Identity());
  }
  std::vector<double> at(const ros::Time& t) {
    std::lock_guard<std::mutex> lock(mutex_);
    return motion_(t);
  }
  const CollisionChecker& checker() const { return checker_; }

 private:
  void tick(const ros::WallTimerEvent&) {
    const ros::Time now = ros::Time::now();
    const std::vector<double> q = at(now);
    sensor_msgs::JointState state = joint_state(names_, q);
    state.header.stamp = now;
    pub_.publish(state);
    tf_.sendTransform(transform_msg("world", "hand_camera", camera_at(q), now));
  }
  ros::NodeHandle nh_;
  ros::Publisher pub_;
  tf2_ros::TransformBroadcaster tf_;
  std::vector<std::string> names_;
  CollisionChecker checker_;
  std::mutex mutex_;
  Motion motion_;
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
    driver_ = new Driver(checker.model().variable_names(), checker);
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
    for (const char* node : {kNoReturn, kOctomapRule}) {
      EXPECT_EQ(inserted.at(node), sent_) << node;
    }
  }
  // A depth image of the boxes from the camera, stamped now, shown.
  void show_image(const Transform& camera, const std::vector<Box>& boxes, const std::string& frame) {
    sensor_msgs::PointCloud2 cloud = depth_cloud(camera, boxes, frame);
    cloud.header.stamp = ros::Time::now();
    show(cloud);
  }
  // Every cloud sent was inserted, none dropped or rejected (the waits above only see insertions).
  static void TearDownTestSuite() {
    for (const char* node : {kNoReturn, kOctomapRule}) {
      const CloudCounts c = wait_for_clouds(sent_, 60.0, node);
      EXPECT_EQ(c.inserted, sent_) << node;
      // Each cloud that changed the map gave it a distance field, made one of three ways.
      const std::uint64_t fields = c.fields_in_place + c.fields_copied + c.fields_built;
      EXPECT_GT(fields, 0u) << node;
      EXPECT_LE(fields, c.inserted) << node;
      std::printf("%s: fields in place %llu, copied %llu, built %llu of %llu clouds\n", node, (unsigned long long)c.fields_in_place,
                  (unsigned long long)c.fields_copied, (unsigned long long)c.fields_built, (unsigned long long)c.inserted);
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
    show_image(camera, {box}, "depth_optical");
  }
  ASSERT_GT(count_in(occupied(kNoReturn), lo, hi), 50);
  ASSERT_EQ(count_in(occupied(kNoReturn), lo, hi), count_in(occupied(kOctomapRule), lo, hi));
  int scans = 0;
  for (; scans < 12 && count_in(occupied(kNoReturn), lo, hi) > 0; ++scans) {
    show_image(camera, {}, "depth_optical");
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
    show_image(camera, {box}, "unlisted_optical");
  }
  ASSERT_GT(count_in(occupied(kNoReturn), lo, hi), 50);
  for (int scans = 0; scans < 7; ++scans) {
    show_image(camera, {}, "unlisted_optical");
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
    show_image(camera, {table, unknown, {c - size / 2, c + size / 2}}, "overhead_optical");
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

// A camera on the hand while the arm sweeps (the driver's joint states and the hand camera's tf
// follow the same motion): each cloud is stamped 0.15 s before the newest joint state and
// transform, when the camera looked up to 0.15 rad elsewhere (a pillar 0.8 m away would land 12
// cm off) and the fingers in its view stood elsewhere. Inserted at the camera's pose at the stamp
// and filtered with the arm's state then, every voxel is on the pillar: no ghosts, no finger.
TEST_F(NodeChangingWorld, ACameraOnTheSweepingArmLeavesNoGhosts) {
  const CollisionChecker& robot = driver_->checker();
  const auto& names = robot.model().variable_names();
  const auto index = [&](const std::string& joint) { return std::find(names.begin(), names.end(), joint) - names.begin(); };
  const ros::Time t0 = ros::Time::now();
  // Leaning back towards -x (away from the other tests' obstacles), yawing through +-0.3 rad.
  const auto motion = [=](const ros::Time& t) {
    std::vector<double> q(names.size(), 0.0);
    q[index("joint1")] = 0.3 * std::sin((t - t0).toSec() / 0.3);
    q[index("joint2")] = -0.6;
    q[index("joint3")] = -0.6;
    return q;
  };
  std::vector<double> middle = motion(t0);
  const Transform aim = driver_->camera_at(middle);
  const Vec3 centre = aim.t + 0.6 * aim.R.col(2);
  const Vec3 lo(centre.x() - 0.05, centre.y() - 0.05, 0.0), hi(centre.x() + 0.05, centre.y() + 0.05, 1.2);  // the pillar
  Environment world(0.02);
  world.add_object("pillar", ObjectShape::box(hi - lo), Transform::Translation(0.5 * (lo + hi)));
  driver_->follow(motion);
  // (The joint states and transforms of the motion must reach the nodes before the first stamp.)
  ros::WallDuration(1.0).sleep();
  for (int k = 0; k < 8; ++k) {
    ros::WallDuration(0.2).sleep();
    const ros::Time stamp = ros::Time::now() - ros::Duration(0.15);
    const std::vector<double> q = driver_->at(stamp);
    const Transform camera = driver_->camera_at(q);
    std::vector<ScanPoint> points;  // a 64 x 48 depth image: the pillar and the fingers, in the camera's frame
    for (std::uint32_t v = 0; v < kHeight; ++v) {
      for (std::uint32_t u = 0; u < kWidth; ++u) {
        const Vec3 ray = camera.R * Vec3((u - kCx) / kFx, (v - kCy) / kFy, 1.0).normalized();
        const RayCastResult hit = robot.cast_ray(q.data(), world, camera.t, ray, 2.5);
        points.push_back(hit.hit ? (camera.inverse() * hit.point).cast<float>() : ScanPoint(kNan, kNan, kNan));
      }
    }
    sensor_msgs::PointCloud2 cloud = to_cloud_msg(points, "hand_camera");
    cloud.header.stamp = stamp;
    show(cloud);
  }
  driver_->follow([=](const ros::Time&) { return middle; });
  for (const char* node : {kNoReturn, kOctomapRule}) {
    const std::vector<Vec3> cells = occupied(node);
    const int on_pillar = count_in(cells, lo - Vec3::Constant(0.02), hi + Vec3::Constant(0.02));
    EXPECT_GT(on_pillar, 30) << node;
    // Around the pillar and the arm, away from the other tests' obstacles (all at x > 0.4).
    EXPECT_EQ(count_in(cells, Vec3(-2.0, -1.0, -0.1), Vec3(0.3, 1.0, 1.6)), on_pillar) << node << ": voxels off the pillar";
  }
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_changing_world"); }
