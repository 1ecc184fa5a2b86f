// The collision_checker node (docs/design.md): the checker's queries as ROS services, the
// obstacle octree fed by point clouds through tf2, markers and diagnostics.
//
// Threads: services, joint_states and timers run on the global callback queue, served by a
// multi-threaded spinner; clouds run on a queue of their own with one thread, so a long scan
// insertion never delays a query. Queries read an immutable snapshot of the environment
// (EnvironmentStore): they never see a half-updated octree and never wait for an insertion.
// Construction throws NodeStartupError when the node cannot run, with a message that says why.
#pragma once

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include <ros/callback_queue.h>
#include <ros/message_event.h>
#include <ros/console.h>
#include <ros/node_handle.h>
#include <ros/spinner.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/JointState.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include "bvh_collision/AttachObject.h"
#include "bvh_collision/CastRay.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/session/joint_states.h"
#include "bvh_collision/session/robot_checkers.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/CheckMotions.h"
#include "bvh_collision/CheckState.h"
#include "bvh_collision/CheckStates.h"
#include "bvh_collision/PinWorld.h"
#include "bvh_collision/ClearBox.h"
#include "bvh_collision/DetachObject.h"
#include "bvh_collision/RemoveCollisionObject.h"
#include "bvh_collision/LoadScene.h"
#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/SaveScene.h"
#include "bvh_collision/SetAllowedCollisions.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/world/environment_store.h"
#include "bvh_collision/geometry/limits.h"
#include "bvh_collision/robot/joint_state_history.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/ros/conversions.h"
#include "bvh_collision/ros/latency_stats.h"

namespace bvh_collision {

class NodeStartupError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The node's private parameters (docs/design.md, and the node's own below the line).
struct NodeParameters {
  std::string world_frame;  // empty until resolved: then the URDF root link
  double resolution = 0.02;
  double padding = 0.0;
  std::map<std::string, double> link_padding;
  double tolerance = 0.0;
  // Seconds a world version pinned with pin_world lives without a use (then a query naming it is
  // an error that names this parameter).
  double pin_timeout = 60.0;
  // Bounded-error link proxy levels (m) (narrowphase/link_proxy.h), built after start-up on a thread
  // of their own, coarsest first, each put to use as it is done (until then queries at a
  // tolerance take the exact path, within the same contract). A finer level predicted to need
  // more than kProxySphereBudget spheres is skipped (with those after it). 2 mm is not a default:
  // slow to build, and no faster than the exact path (docs/performance.md).
  std::vector<double> proxy_levels = {0.005, 0.01, 0.02};
  // Where built link proxies and clearance grids are kept by content (narrowphase/link_proxy_cache.h,
  // model/pair_clearance_cache.h), so that a restart reads them instead of building them again. Unset: $ROS_HOME (or ~/.ros)/bvh_collision/proxy_cache;
  // empty: none.
  std::string proxy_cache;
  // Build the octree's distance field after each cloud (on the cloud thread), so that boolean
  // checks and motions skip the octree for links it clears.
  bool distance_field = true;
  // Octree bounds in world_frame; unset: a cube of half-edge reach + 0.5 m around the root link.
  std::optional<Vec3> workspace_min, workspace_max;
  double max_range = 5.0;
  double self_filter_padding = 0.02;
  // Points on or within this of a collision object or a carried object are not voxels either
  // (world/object_filter.h): a known object is not counted twice. Unset: self_filter_padding.
  std::optional<double> object_padding;
  // Rays with no return (a depth image's NaN pixels) clear along their pixel's ray up to max_range,
  // and rays that end past the workspace or max_range clear inside it instead of being dropped
  // (ScanOptions::clip_rays_to_workspace). Off: the tree is OctoMap's insertPointCloud's.
  bool clear_no_return = false;
  // A NaN pixel's ray: from the latest sensor_msgs/CameraInfo on ~camera_info (a topic name; empty:
  // none) of the cloud's camera, else ~camera_intrinsics [fx, fy, cx, cy], else fitted to the
  // cloud's own valid points, else the camera's last fit; each only if the cloud agrees with it.
  std::string camera_info_topic;
  std::optional<PinholeCamera> camera_intrinsics;
  // Probabilities, as octomap_server takes them (OctoMap's defaults).
  double sensor_hit = 0.7, sensor_miss = 0.4, sensor_min = 0.1192, sensor_max = 0.971;
  std::string octree_file;
  std::string scene_file;  // a MoveIt .scene file of collision objects to start with (load_scene's)
  // ---
  double cloud_transform_timeout = 0.2;  // s to wait for a cloud's transform at its stamp
  // The self filter places the robot at a cloud's stamp from the joint states of the last
  // `joint_state_history` s (interpolated); a cloud older than that, or stamped more than
  // `joint_state_lead` s after the newest joint state, is dropped and counted.
  double joint_state_history = 10.0, joint_state_lead = 0.1;
  // A query that takes joint values from joint_states (joints it leaves out; cast_ray) answers an
  // error once the last joint state is older than this (s): the robot's pose is no longer known.
  // 0: never. Before the first joint state the neutral state is used, as always.
  double joint_state_timeout = 1.0;
  // tf keeps answering a lookup of the latest transform with the last one it heard, however old:
  // a query that places the root link (or an object's frame) in world_frame through a transform
  // that is not static answers an error once that transform is older than this (s). 0: never.
  double tf_timeout = 1.0;
  double diagnostic_period = 1.0;        // s between /diagnostics messages (diagnostic_updater's ~diagnostic_period)
  double marker_rate = 2.0;              // Hz, at most, for occupied_cells (only when subscribed)
  double marker_alpha = 1.0;             // opacity of the occupied_cells cubes (below 1: the cloud shows through)
  int service_threads = 4;               // spinner threads for services (batches use every core anyway)
  // The nice value (0 to 19) of the cloud thread and of the pool its insertions fan out on: the
  // scheduler serves queries first and the map takes the CPU they leave (0: as the queries).
  int cloud_nice = 10;
  // ~max_motion_states, ~max_batch_states, ~max_cloud_points, ~max_ray_voxels,
  // ~max_object_triangles, ~max_robot_links, ~max_checked_pairs (geometry/limits.h).
  Limits limits;

  OccupancyModel occupancy_model() const;
};

// About 113 bytes a sphere kept: at most ~57 MB for the finest level. pr2's 5 mm level (415,194
// spheres, 47 MB, 6.4 s to build on one core) fits, and makes its exact certified plans faster
// (its exact mesh distances start at half the growth: docs/planning.md).
constexpr std::size_t kProxySphereBudget = 500000;
constexpr double kMostServiceThreads = 64;  // ~service_threads: 1 to this

// Reads and validates the private parameters; throws NodeStartupError on a bad value.
NodeParameters read_node_parameters(const ros::NodeHandle& private_nh);

class CollisionCheckerNode {
 public:
  CollisionCheckerNode(ros::NodeHandle nh, ros::NodeHandle private_nh);
  ~CollisionCheckerNode();
  CollisionCheckerNode(const CollisionCheckerNode&) = delete;
  CollisionCheckerNode& operator=(const CollisionCheckerNode&) = delete;

  // Sets ~ready (true): call once the services are served (the spinner runs). Launch tests and
  // clients wait for it; the robot summary (~robot) is set before any service is advertised.
  void mark_ready();

  const RobotSummary& robot_summary() const { return summary_; }
  const NodeParameters& parameters() const { return params_; }

 private:
  // The service fuzz target (test/fuzz/message_targets.cpp) calls the handlers directly.
  friend struct NodeFuzzAccess;

  // Start-up (collision_checker_node.cpp).
  void load_robot();
  Environment initial_octree() const;       // ~octree_file's, or an empty one
  Environment initial_environment() const;  // that, with ~scene_file's objects
  void advertise();
  void publish_status();
  void log_solidity();
  // The checker queries use now: proxy levels join it as they are built. Hold the pointer while
  // using references into it (a swap may free the old one).
  std::shared_ptr<const CollisionChecker> checker() const { return checkers_->current(); }
  // The checker a query on snapshot `env` uses (RobotCheckers::for_snapshot: what it carries). A
  // query takes the snapshot first and this from it, so it sees an object on the link or in the
  // world, never both or neither.
  std::shared_ptr<const CollisionChecker> checker_for(const std::shared_ptr<const Environment>& env) const {
    return checkers_->for_snapshot(env);
  }
  // Where link `link` is in world_frame now (joint_states, tf2): attaching and detaching fix an
  // object's pose between the two frames with it.
  Transform link_in_world(int link) const;

  // The robot's state and pose (collision_checker_node.cpp).
  void on_joint_state(const sensor_msgs::JointState::ConstPtr& msg);
  std::vector<double> current_state() const;
  // The current state as the base of a request that sets the variables in `columns` (-1: none):
  // a RequestError when it needs a joint value from joint_states that have stopped.
  std::vector<double> current_state_for(const std::vector<int>& columns) const;
  // The joint values at a cloud's stamp (joint_state_history), waiting up to `timeout` for the
  // joint states to reach it (they often come after the cloud); the current state for a zero
  // stamp or before any joint_states; nothing when the stamp lies outside the history.
  std::optional<std::vector<double>> state_at(const ros::Time& stamp, const ros::WallDuration& timeout) const;
  // The root link in world_frame at `stamp` (0: the latest); throws RequestError when tf2 cannot
  // tell within `timeout`.
  Transform root_pose(const ros::Time& stamp, const ros::Duration& timeout = ros::Duration(0)) const;
  // The latest transform from `frame` to world_frame; a RequestError when a dynamic one is older
  // than ~tf_timeout.
  geometry_msgs::TransformStamped latest_transform(const std::string& frame) const;
  // `frame` to world_frame, the latest transform; throws RequestError naming the frame.
  Transform frame_to_world(const std::string& frame) const;
  void require_geometry() const;

  // Queries (query_services.cpp).
  bool check_state(CheckState::Request& req, CheckState::Response& res);
  bool check_states(CheckStates::Request& req, CheckStates::Response& res);
  bool check_motion(CheckMotion::Request& req, CheckMotion::Response& res);
  bool check_motions(CheckMotions::Request& req, CheckMotions::Response& res);
  // The prepared scene certified motions go through for this snapshot, these checks and this
  // root pose (RobotCheckers::prepared): the one kept since the last such request when nothing changed.
  std::shared_ptr<const SceneChecker> scene_checker(const std::shared_ptr<const Environment>& env, bool self,
                                                    bool environment, const Transform& root) const {
    return checkers_->prepared(env, self, environment, root, params_.tolerance);
  }
  bool cast_ray(CastRay::Request& req, CastRay::Response& res);
  bool pin_world(PinWorld::Request& req, PinWorld::Response& res);
  // The world a query names: the latest (version 0) or a version pinned with pin_world (a
  // RequestError naming ~pin_timeout when it is not, or no longer, pinned).
  EnvironmentStore::Pin world(std::uint64_t version);
  void answer_check_state(const CheckState::Request& req, CheckState::Response& res);
  void self_part(const CollisionChecker& checker, const double* state, const CheckState::Request& req, double tolerance,
                 const Transform& root, CheckState::Response& res);
  void environment_part(const CollisionChecker& checker, const double* state, const Environment& env,
                        const CheckState::Request& req, double tolerance, const Transform& root, CheckState::Response& res);
  double request_tolerance(double requested) const;
  // Runs `handler` with the request timed under `name`; a RequestError (or any exception) becomes
  // the response's error, so no request can take the node down.
  template <class Response, class Handler>
  bool serve(const char* name, Response& res, Handler&& handler);

  // The environment (environment_services.cpp).
  void on_cloud(const ros::MessageEvent<const sensor_msgs::PointCloud2>& event);
  void count_superseded(const ros::MessageEvent<const sensor_msgs::PointCloud2>& event);
  void insert_cloud(const sensor_msgs::PointCloud2& msg);
  void on_camera_info(const sensor_msgs::CameraInfo& msg);
  // The rays of an organized cloud's NaN pixels, `max_range` long, in the cloud's frame
  // (~clear_no_return; empty for an unorganized cloud or one no camera model fits, counted).
  std::vector<ScanPoint> no_return_rays(const sensor_msgs::PointCloud2& msg, const std::vector<ScanPoint>& points);
  bool clear_environment(std_srvs::Empty::Request& req, std_srvs::Empty::Response& res);
  bool clear_box(ClearBox::Request& req, ClearBox::Response& res);
  bool set_collision_object(SetCollisionObject::Request& req, SetCollisionObject::Response& res);
  bool remove_collision_object(RemoveCollisionObject::Request& req, RemoveCollisionObject::Response& res);
  bool save_octree(SaveOctree::Request& req, SaveOctree::Response& res);
  bool load_scene(LoadScene::Request& req, LoadScene::Response& res);
  bool save_scene(SaveScene::Request& req, SaveScene::Response& res);
  bool set_allowed_collisions(SetAllowedCollisions::Request& req, SetAllowedCollisions::Response& res);
  bool attach_object(AttachObject::Request& req, AttachObject::Response& res);
  bool detach_object(DetachObject::Request& req, DetachObject::Response& res);
  std::vector<CollisionObject> attached_shapes(const AttachObject::Request& req, const Transform& link_world) const;
  SceneFile read_scene_for_node(const std::string& path) const;
  void attach_scene_objects(const SceneFile& scene, Environment& env, const std::string& path) const;

  // Output (node_output.cpp).
  void publish_occupied_cells(const ros::WallTimerEvent&);
  void publish_contacts(const std::vector<Contact>& contacts);
  void publish_diagnostics(const ros::WallTimerEvent&);

  ros::NodeHandle nh_, private_nh_;
  NodeParameters params_;
  std::shared_ptr<urdf::ModelInterface> urdf_;
  RobotSummary summary_;
  std::vector<std::string> solid_links_, open_meshes_;  // link_solidity(), for the log and parameters
  PackageResolver resolver_;
  std::unique_ptr<RobotCheckers> checkers_;  // the robot's, the carried objects', the prepared scene
  std::unique_ptr<const JointValueMap> joint_map_;
  std::string root_link_;
  bool has_geometry_ = false;
  std::unique_ptr<EnvironmentStore> store_;
  std::unique_ptr<JointStates> joints_;  // from joint_states: the current state and its history

  tf2_ros::Buffer tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;

  ros::CallbackQueue cloud_queue_;
  std::unique_ptr<ThreadPool> cloud_pool_;  // the cloud thread's fan-outs, at ~cloud_nice
  std::unique_ptr<ros::AsyncSpinner> cloud_spinner_;
  std::vector<ros::ServiceServer> services_;
  ros::Subscriber joint_state_sub_, cloud_sub_, camera_info_sub_;
  // Camera models for rays with no return: the last CameraInfo (~camera_info) with its frame and
  // image size, and the last model fitted to each camera's clouds (by frame and size), for a
  // cloud with too few points to fit (a box taken away with nothing behind it).
  struct CameraModel {
    PinholeCamera camera;
    std::string frame;
    std::uint32_t width = 0, height = 0;
  };
  mutable std::mutex camera_mutex_;
  std::optional<CameraModel> camera_info_;
  std::map<std::tuple<std::string, std::uint32_t, std::uint32_t>, PinholeCamera> fitted_cameras_;
  ros::Publisher cells_pub_, contacts_pub_, diagnostics_pub_;
  ros::WallTimer cells_timer_, diagnostics_timer_;
  std::uint64_t cells_version_ = ~std::uint64_t(0);  // the environment version last drawn
  std::uint32_t cells_subscribers_ = 0;
  std::atomic<double> last_contacts_time_{0.0};
  std::uint64_t clouds_lost_reported_ = 0;  // dropped + rejected at the last diagnostics
  std::map<std::string, std::uint32_t> last_cloud_seq_;  // by publisher; the cloud thread's alone

  // Every cloud sent to the node is received or superseded; every one received is inserted,
  // dropped (no transform, no joint state at its stamp) or rejected (malformed, over the limit).
  struct CloudCounters {
    std::atomic<std::uint64_t> received{0}, inserted{0}, dropped_transform{0}, dropped_state{0}, rejected{0};
    std::atomic<std::uint64_t> superseded{0};  // replaced by a newer cloud before the node took it (seq gaps)
    std::atomic<std::uint64_t> over_limit{0};  // more points than ~max_cloud_points
    std::atomic<std::uint64_t> points{0}, skipped_invalid{0}, skipped_outside{0}, skipped_workspace{0};
    std::atomic<std::uint64_t> on_robot{0}, shadowed{0}, on_objects{0};
    std::atomic<std::uint64_t> no_return{0};           // rays of NaN pixels cast to max_range
    std::atomic<std::uint64_t> no_return_unplaced{0};  // NaN pixels of a cloud no camera model fits
    std::atomic<double> last_insert_seconds{0.0};
    // the map's distance field after each: made in place (written over one no query holds any
    // more, or a new version beside one a query or pin holds), copied into a grid of its own
    // (and updated) because every older one usable was still held, or built anew
    std::atomic<std::uint64_t> fields_in_place{0}, fields_copied{0}, fields_built{0};
  } clouds_;
  std::map<std::string, LatencyStats> latency_;  // keys fixed at start-up: lookups need no lock
  // Robot states the queries checked (a motion's every step): a test bounds a request's work by it.
  std::atomic<std::uint64_t> states_checked_{0};
};

template <class Response, class Handler>
bool CollisionCheckerNode::serve(const char* name, Response& res, Handler&& handler) {
  const auto start = std::chrono::steady_clock::now();
  latency_.at(name).begin();
  bool failed = false;
  try {
    handler();
  } catch (const std::invalid_argument& e) {  // RequestError, or the checker refusing an argument
    res = Response();
    res.error = e.what();
    failed = true;
  } catch (const std::exception& e) {  // not the request's fault: say so in the log as well
    ROS_ERROR_STREAM("collision_checker: " << name << " failed: " << e.what());
    res = Response();
    res.error = std::string("internal error: ") + e.what();
    failed = true;
  }
  latency_.at(name).record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), failed);
  return true;  // the error travels in the response; false would only tell the client "call failed"
}

}  // namespace bvh_collision
