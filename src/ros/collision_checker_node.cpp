// Start-up, the robot's state from joint_states, and poses from tf2.
#include "bvh_collision/ros/collision_checker_node.h"

#include <algorithm>

#include <sstream>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/console.h>
#include <visualization_msgs/MarkerArray.h>

#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/robot/link_solidity.h"

namespace bvh_collision {

namespace {

const char* const kServices[] = {"check_state", "check_states", "check_motion", "check_motions", "cast_ray", "clear_environment",
                                 "clear_box", "set_collision_object", "remove_collision_object", "save_octree",
                                 "load_scene", "save_scene", "set_allowed_collisions", "attach_object",
                                 "detach_object", "pin_world"};

}  // namespace

CollisionCheckerNode::CollisionCheckerNode(ros::NodeHandle nh, ros::NodeHandle private_nh)
    : nh_(std::move(nh)), private_nh_(std::move(private_nh)), resolver_(PackageResolver::from_environment()) {
  // A value left by an earlier run of a node of this name is not this one's.
  private_nh_.setParam("ready", false);
  params_ = read_node_parameters(private_nh_);
  for (const char* name : kServices) latency_[name];
  load_robot();
  store_ = std::make_unique<EnvironmentStore>(initial_environment());
  params_.resolution = store_->snapshot()->octree().resolution();  // an octree file may set it
  tf_listener_ = std::make_unique<tf2_ros::TransformListener>(tf_buffer_, nh_);
  ROS_INFO_STREAM("collision_checker: " << summary_.to_string() << "; world frame '" << params_.world_frame
                                        << "', octree resolution " << params_.resolution << " m, "
                                        << checker()->checked_pairs().size() << " link pairs checked");
  log_solidity();
  publish_status();  // before any service: a client that sees one sees the whole summary
  advertise();
  if (has_geometry_) checkers_->start_proxy_levels();
}

CollisionCheckerNode::~CollisionCheckerNode() {
  if (ros::ok()) private_nh_.setParam("ready", false);
  if (cloud_spinner_) cloud_spinner_->stop();
  checkers_.reset();  // stops the proxy builds (at their next link) and waits for them
}

void CollisionCheckerNode::mark_ready() {
  private_nh_.setParam("ready", true);
  ROS_INFO("collision_checker: ready (%zu services)", services_.size());
}

void CollisionCheckerNode::load_robot() {
  std::string xml;
  if (!nh_.getParam("robot_description", xml)) {
    throw NodeStartupError("parameter '" + nh_.resolveName("robot_description") +
                           "' is not set (or is not a string): it must hold the robot's URDF");
  }
  try {
    urdf_ = parse_robot_description(xml);
  } catch (const RobotDescriptionError& e) {
    throw NodeStartupError("parameter '" + nh_.resolveName("robot_description") + "': " + e.what());
  }
  summary_ = summarize(*urdf_);
  // Before any mesh is read: a robot of thousands of links is refused at once.
  try {
    check_limit("robot '" + summary_.name + "' with its links", double(summary_.links), params_.limits.robot_links,
                "max_robot_links");
  } catch (const LimitExceeded& e) {
    throw NodeStartupError(e.what());
  }
  if (params_.world_frame.empty()) params_.world_frame = summary_.root_link;
  RobotModel model = [&] {
    try {
      return RobotModel::from_urdf(*urdf_, resolver_);
    } catch (const RobotLoadError& e) {
      throw NodeStartupError(std::string("robot '") + summary_.name + "': " + e.what());
    }
  }();
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  std::string srdf;
  if (nh_.getParam("robot_description_semantic", srdf) && !srdf.empty()) {
    try {
      const Srdf semantic = parse_srdf(srdf, &model);
      for (const std::string& w : semantic.warnings) ROS_WARN_STREAM("collision_checker: " << w);
      for (const std::string& name : apply_srdf(semantic, model, acm)) {
        ROS_WARN_STREAM("collision_checker: the SRDF names '" << name << "', which the URDF does not have");
      }
    } catch (const std::invalid_argument& e) {
      throw NodeStartupError("parameter '" + nh_.resolveName("robot_description_semantic") + "': " + e.what());
    }
  }
  for (const auto& [link, padding] : params_.link_padding) {
    if (model.link_index(link) < 0) throw NodeStartupError("parameter ~link_padding names unknown link '" + link + "'");
  }
  has_geometry_ = has_collision_geometry(model);
  root_link_ = model.links()[model.root_link()].name;
  try {
    joints_ = std::make_unique<JointStates>(model, neutral_state(model), params_.joint_state_history, params_.joint_state_lead);
  } catch (const std::invalid_argument& e) {
    throw NodeStartupError(std::string("parameters ~joint_state_history and ~joint_state_lead: ") + e.what());
  }
  CheckerOptions options;
  options.padding = params_.padding;
  options.link_padding = params_.link_padding;
  options.limits = params_.limits;
  options.proxy_cache = params_.proxy_cache;
  // The clearance grids and the proxy levels come later, built beside the queries
  // (session/robot_checkers.h): the same answers meanwhile, and no start waits on them.
  options.pair_clearance_cells = 0;
  try {
    checkers_ = std::make_unique<RobotCheckers>(CollisionChecker(std::move(model), std::move(acm), options), params_.proxy_levels,
                                                kProxySphereBudget, [](SessionLogLevel level, const std::string& line) {
                                                  if (level == SessionLogLevel::kInfo) ROS_INFO_STREAM("collision_checker: " << line);
                                                  else if (level == SessionLogLevel::kWarning) ROS_WARN_STREAM("collision_checker: " << line);
                                                  else ROS_ERROR_STREAM("collision_checker: " << line);
                                                },
                                                CheckerOptions().pair_clearance_cells);
  } catch (const LimitExceeded& e) {
    throw NodeStartupError(std::string("robot '") + summary_.name + "': " + e.what());
  }
  joint_map_ = std::make_unique<const JointValueMap>(checker()->model());
}

Environment CollisionCheckerNode::initial_octree() const {
  const OccupancyModel model = params_.occupancy_model();
  Environment env(params_.resolution, model);
  if (params_.octree_file.empty()) return env;
  Octree loaded = [&] {
    try {
      return load_octree(params_.octree_file);
    } catch (const std::exception& e) {
      throw NodeStartupError(std::string("parameter ~octree_file: ") + e.what());
    }
  }();
  // The file's voxels and values, this node's sensor model for what comes next.
  std::stringstream nodes;
  loaded.write_nodes(nodes);
  if (loaded.resolution() != params_.resolution) {
    ROS_WARN_STREAM("collision_checker: ~octree_file has resolution " << loaded.resolution()
                                                                      << " m, which replaces ~resolution "
                                                                      << params_.resolution << " m");
  }
  Environment from_file(loaded.resolution(), model);
  from_file.octree() = Octree::read_nodes(nodes, loaded.resolution(), model);
  ROS_INFO_STREAM("collision_checker: started from '" << params_.octree_file << "' ("
                                                      << from_file.octree().node_count() << " nodes)");
  return from_file;
}

// The octree to start from, with the collision objects of ~scene_file (a malformed file stops the
// node with a message naming its line and field).
Environment CollisionCheckerNode::initial_environment() const {
  Environment env = initial_octree();
  if (params_.scene_file.empty()) return env;
  try {
    const SceneFile scene = read_scene_file(params_.scene_file);
    for (CollisionObject& o : scene.collision_objects()) env.add_object(std::move(o));
    ROS_INFO_STREAM("collision_checker: started with the " << scene.objects.size() << " objects (" << scene.shape_count()
                                                           << " shapes) of scene '" << scene.name << "'");
  } catch (const std::exception& e) {
    throw NodeStartupError(std::string("parameter ~scene_file: ") + e.what());
  }
  return env;
}

void CollisionCheckerNode::advertise() {
  services_.push_back(private_nh_.advertiseService("check_state", &CollisionCheckerNode::check_state, this));
  services_.push_back(private_nh_.advertiseService("check_states", &CollisionCheckerNode::check_states, this));
  services_.push_back(private_nh_.advertiseService("check_motion", &CollisionCheckerNode::check_motion, this));
  services_.push_back(private_nh_.advertiseService("check_motions", &CollisionCheckerNode::check_motions, this));
  services_.push_back(private_nh_.advertiseService("cast_ray", &CollisionCheckerNode::cast_ray, this));
  services_.push_back(private_nh_.advertiseService("pin_world", &CollisionCheckerNode::pin_world, this));
  services_.push_back(
      private_nh_.advertiseService("clear_environment", &CollisionCheckerNode::clear_environment, this));
  services_.push_back(private_nh_.advertiseService("clear_box", &CollisionCheckerNode::clear_box, this));
  services_.push_back(
      private_nh_.advertiseService("set_collision_object", &CollisionCheckerNode::set_collision_object, this));
  services_.push_back(private_nh_.advertiseService("remove_collision_object",
                                                   &CollisionCheckerNode::remove_collision_object, this));
  services_.push_back(private_nh_.advertiseService("save_octree", &CollisionCheckerNode::save_octree, this));
  services_.push_back(private_nh_.advertiseService("load_scene", &CollisionCheckerNode::load_scene, this));
  services_.push_back(
      private_nh_.advertiseService("set_allowed_collisions", &CollisionCheckerNode::set_allowed_collisions, this));
  services_.push_back(private_nh_.advertiseService("save_scene", &CollisionCheckerNode::save_scene, this));
  services_.push_back(private_nh_.advertiseService("attach_object", &CollisionCheckerNode::attach_object, this));
  services_.push_back(private_nh_.advertiseService("detach_object", &CollisionCheckerNode::detach_object, this));

  joint_state_sub_ = nh_.subscribe("joint_states", 10, &CollisionCheckerNode::on_joint_state, this,
                                   ros::TransportHints().tcpNoDelay());
  // Clouds on their own queue and thread; queue size 1: a checker that falls behind drops old
  // clouds rather than insert stale ones.
  ros::NodeHandle cloud_nh(nh_);
  cloud_nh.setCallbackQueue(&cloud_queue_);
  cloud_pool_ = std::make_unique<ThreadPool>(std::max(1u, std::thread::hardware_concurrency()) - 1, params_.cloud_nice);
  cloud_sub_ = cloud_nh.subscribe("obstacle_cloud", 1, &CollisionCheckerNode::on_cloud, this);
  if (!params_.camera_info_topic.empty()) {
    camera_info_sub_ = cloud_nh.subscribe(params_.camera_info_topic, 1, &CollisionCheckerNode::on_camera_info, this);
  }
  cloud_spinner_ = std::make_unique<ros::AsyncSpinner>(1, &cloud_queue_);
  cloud_spinner_->start();

  cells_pub_ = private_nh_.advertise<visualization_msgs::MarkerArray>("occupied_cells", 1);
  // Latched: rviz started after a query still shows its contacts.
  contacts_pub_ = private_nh_.advertise<visualization_msgs::MarkerArray>("contacts", 1, true);
  diagnostics_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 1);
  cells_timer_ = nh_.createWallTimer(ros::WallDuration(1.0 / params_.marker_rate),
                                     &CollisionCheckerNode::publish_occupied_cells, this);
  diagnostics_timer_ =
      nh_.createWallTimer(ros::WallDuration(params_.diagnostic_period), &CollisionCheckerNode::publish_diagnostics, this);
}

// One line: which links are solids (a link inside one collides) and which meshes are open, and
// why; the same lists as parameters (robot/solid_links, robot/open_meshes).
void CollisionCheckerNode::log_solidity() {
  const std::shared_ptr<const CollisionChecker> checker = this->checker();  // keeps `m` alive
  const RobotModel& m = checker->model();
  const LinkSolidity solidity = link_solidity(m);
  solid_links_.clear();
  open_meshes_.clear();
  for (const int l : solidity.solid_links) solid_links_.push_back(m.links()[l].name);
  for (const OpenMesh& open : solidity.open_meshes) open_meshes_.push_back(describe(open, m));
  std::ostringstream line;
  line << "collision_checker: " << solid_links_.size() << " solid links";
  for (std::size_t i = 0; i < solid_links_.size(); ++i) {
    line << (i ? ", " : " (") << solid_links_[i] << (i + 1 == solid_links_.size() ? ")" : "");
  }
  line << "; " << open_meshes_.size() << " open meshes (not solids)";
  for (const std::string& open : open_meshes_) line << "; " << open;
  ROS_INFO_STREAM(line.str());
}

namespace {

XmlRpc::XmlRpcValue string_list(const std::vector<std::string>& items) {
  XmlRpc::XmlRpcValue list;
  list.setSize(static_cast<int>(items.size()));
  for (std::size_t i = 0; i < items.size(); ++i) list[static_cast<int>(i)] = items[i];
  return list;
}

}  // namespace

// The robot summary as one dictionary (~robot), one call to the master: a reader sees all of it
// or none of it (set one key at a time, a reader between two calls saw half a summary).
void CollisionCheckerNode::publish_status() {
  private_nh_.setParam("world_frame", params_.world_frame);
  private_nh_.setParam("resolution", params_.resolution);
  XmlRpc::XmlRpcValue robot;
  robot["name"] = summary_.name;
  robot["root_link"] = summary_.root_link;
  robot["links"] = static_cast<int>(summary_.links);
  robot["joints"] = static_cast<int>(summary_.joints);
  robot["collision_elements"] = static_cast<int>(summary_.collision_elements);
  robot["variables"] = string_list(checker()->model().variable_names());
  robot["checked_pairs"] = static_cast<int>(checker()->checked_pairs().size());
  robot["reach"] = checker()->reach();
  robot["solid_links"] = string_list(solid_links_);
  robot["open_meshes"] = string_list(open_meshes_);
  private_nh_.setParam("robot", robot);
}

void CollisionCheckerNode::on_joint_state(const sensor_msgs::JointState::ConstPtr& msg) {
  if (msg->position.size() != msg->name.size()) {
    ROS_WARN_THROTTLE(5.0, "collision_checker: joint_states with %zu names and %zu positions ignored",
                      msg->name.size(), msg->position.size());
    return;
  }
  // The merged state at the message's stamp (its arrival when unstamped): what a cloud taken
  // then must be filtered against.
  const ros::Time now = ros::Time::now();
  joints_->record(msg->name, msg->position, (msg->header.stamp.isZero() ? now : msg->header.stamp).toSec(), now.toSec());
}

std::vector<double> CollisionCheckerNode::current_state() const { return joints_->current(); }

std::vector<double> CollisionCheckerNode::current_state_for(const std::vector<int>& columns) const {
  const std::size_t n = checker()->model().variable_count();
  std::vector<char> given(n, 0);
  for (const int c : columns) {
    if (c >= 0) given[c] = 1;
  }
  const bool needs_joint_states = std::find(given.begin(), given.end(), 0) != given.end();
  const std::optional<double> last = joints_->last_arrival();
  if (needs_joint_states && params_.joint_state_timeout > 0.0 && last) {
    const double age = ros::Time::now().toSec() - *last;
    if (age > params_.joint_state_timeout) {
      throw RequestError("the last joint_states arrived " + std::to_string(age) + " s ago (~joint_state_timeout " +
                         std::to_string(params_.joint_state_timeout) + " s): the joints this request leaves out " +
                         "are not known; give every joint, or restore joint_states");
    }
  }
  return joints_->current();
}

std::optional<std::vector<double>> CollisionCheckerNode::state_at(const ros::Time& stamp,
                                                                 const ros::WallDuration& timeout) const {
  return joints_->at(stamp.isZero() ? 0.0 : stamp.toSec(), timeout.toSec());
}

// The latest transform from `frame` to world_frame, unless a dynamic one has gone quiet.
geometry_msgs::TransformStamped CollisionCheckerNode::latest_transform(const std::string& frame) const {
  geometry_msgs::TransformStamped t = tf_buffer_.lookupTransform(params_.world_frame, frame, ros::Time(0));
  if (params_.tf_timeout > 0.0 && !t.header.stamp.isZero()) {  // static transforms carry stamp 0 here
    const double age = (ros::Time::now() - t.header.stamp).toSec();
    if (age > params_.tf_timeout) {
      throw RequestError("the latest transform from '" + frame + "' to '" + params_.world_frame + "' is " +
                         std::to_string(age) + " s old (~tf_timeout " + std::to_string(params_.tf_timeout) +
                         " s): tf has stopped, so where it is now is unknown");
    }
  }
  return t;
}

Transform CollisionCheckerNode::link_in_world(int link) const {
  const std::vector<double> state = current_state_for({});
  std::vector<Transform> poses;
  forward_kinematics(checker()->model(), state.data(), poses);
  return root_pose(ros::Time(0)) * poses[static_cast<std::size_t>(link)];
}

Transform CollisionCheckerNode::root_pose(const ros::Time& stamp, const ros::Duration& timeout) const {
  if (params_.world_frame == root_link_) return Transform::Identity();
  try {
    if (stamp.isZero()) return to_transform(latest_transform(root_link_).transform);
    return to_transform(tf_buffer_.lookupTransform(params_.world_frame, root_link_, stamp, timeout).transform);
  } catch (const tf2::TransformException& e) {
    throw RequestError("cannot place the root link '" + root_link_ + "' in world frame '" + params_.world_frame +
                       "': " + e.what());
  }
}

Transform CollisionCheckerNode::frame_to_world(const std::string& frame) const {
  if (frame.empty() || frame == params_.world_frame) return Transform::Identity();
  try {
    return to_transform(latest_transform(frame).transform);
  } catch (const tf2::TransformException& e) {
    throw RequestError("unknown frame '" + frame + "' (no transform to '" + params_.world_frame + "'): " + e.what());
  }
}

void CollisionCheckerNode::require_geometry() const {
  if (!has_geometry_) {
    throw RequestError(no_collision_geometry_error(checker()->model()));
  }
}

}  // namespace bvh_collision
