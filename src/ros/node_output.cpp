// What the node shows: occupied voxels and contacts as markers, and /diagnostics.
#include <algorithm>
#include <cstdio>
#include <limits>
#include <sstream>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <visualization_msgs/MarkerArray.h>

#include "bvh_collision/octree/cube_walk.h"
#include "bvh_collision/ros/collision_checker_node.h"

namespace bvh_collision {

namespace {

visualization_msgs::Marker delete_all(const std::string& frame) {
  visualization_msgs::Marker m;
  m.header.frame_id = frame;
  m.action = visualization_msgs::Marker::DELETEALL;
  return m;
}

visualization_msgs::Marker marker(const std::string& frame, const char* ns, int id, int type) {
  visualization_msgs::Marker m;
  m.header.frame_id = frame;
  m.header.stamp = ros::Time::now();
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  m.color.a = 1.0;
  return m;
}

// Blue (low) to red (high) over [lo, hi]: the usual height colouring of occupancy maps.
std_msgs::ColorRGBA height_colour(double z, double lo, double hi) {
  const double s = hi > lo ? std::clamp((z - lo) / (hi - lo), 0.0, 1.0) : 0.5;
  std_msgs::ColorRGBA c;
  c.r = static_cast<float>(s);
  c.g = static_cast<float>(1.0 - std::abs(2.0 * s - 1.0));
  c.b = static_cast<float>(1.0 - s);
  c.a = 1.0f;
  return c;
}

diagnostic_msgs::KeyValue kv(const std::string& key, const std::string& value) {
  diagnostic_msgs::KeyValue k;
  k.key = key;
  k.value = value;
  return k;
}

std::string ms(double seconds) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", seconds * 1e3);
  return buf;
}

}  // namespace

void CollisionCheckerNode::publish_occupied_cells(const ros::WallTimerEvent&) {
  const std::uint32_t subscribers = cells_pub_.getNumSubscribers();
  if (subscribers == 0) {
    cells_subscribers_ = 0;  // whoever subscribes next gets a full picture
    return;
  }
  const std::uint64_t version = store_->version();
  if (version == cells_version_ && subscribers <= cells_subscribers_) return;
  cells_version_ = version;
  cells_subscribers_ = subscribers;
  const std::shared_ptr<const Environment> env = store_->snapshot();
  const Octree& tree = env->octree();
  // Two walks of the occupied leaves (the colours need the height range first), no list of them.
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for_each_occupied_leaf(tree, [&](const Octree::Leaf& l) {
    const double z = tree.cube_min(l.key).z();
    lo = std::min(lo, z);
    hi = std::max(hi, z);
  });
  // One cube list per depth: a marker has one cube size.
  std::map<int, visualization_msgs::Marker> lists;
  for_each_occupied_leaf(tree, [&](const Octree::Leaf& l) {
    auto [it, fresh] = lists.try_emplace(l.depth);
    visualization_msgs::Marker& m = it->second;
    if (fresh) {
      m = marker(params_.world_frame, "occupied_cells", l.depth, visualization_msgs::Marker::CUBE_LIST);
      m.scale.x = m.scale.y = m.scale.z = tree.cube_size(l.depth);
    }
    const Vec3 c = tree.cube_min(l.key) + Vec3::Constant(0.5 * tree.cube_size(l.depth));
    geometry_msgs::Point p;
    p.x = c.x();
    p.y = c.y();
    p.z = c.z();
    m.points.push_back(p);
    m.colors.push_back(height_colour(c.z(), lo, hi));
    m.colors.back().a = static_cast<float>(params_.marker_alpha);
  });
  visualization_msgs::MarkerArray array;
  array.markers.push_back(delete_all(params_.world_frame));
  for (auto& [depth, m] : lists) array.markers.push_back(std::move(m));
  cells_pub_.publish(array);
}

void CollisionCheckerNode::publish_contacts(const std::vector<Contact>& contacts) {
  // Published (latched) whether or not anyone listens now, at most 10 Hz: a planner may call
  // thousands of times a second.
  const double now = ros::WallTime::now().toSec();
  double last = last_contacts_time_.load();
  if (now - last < 0.1 || !last_contacts_time_.compare_exchange_strong(last, now)) return;
  visualization_msgs::MarkerArray array;
  array.markers.push_back(delete_all(params_.world_frame));
  auto points = marker(params_.world_frame, "contacts", 0, visualization_msgs::Marker::SPHERE_LIST);
  // Cyan: no height colour of the voxels has it, and rviz draws collision geometry red.
  points.scale.x = points.scale.y = points.scale.z = 0.03;
  points.color.g = 1.0f;
  points.color.b = 1.0f;
  for (const Contact& c : contacts) points.points.push_back(c.position);
  array.markers.push_back(points);
  for (std::size_t i = 0; i < contacts.size() && i < 50; ++i) {
    auto arrow = marker(params_.world_frame, "contact_normals", int(i), visualization_msgs::Marker::ARROW);
    arrow.scale.x = 0.005;
    arrow.scale.y = 0.01;
    arrow.color.r = 1.0f;
    arrow.color.g = 0.6f;
    geometry_msgs::Point tip = contacts[i].position;
    tip.x += 0.05 * contacts[i].normal.x;
    tip.y += 0.05 * contacts[i].normal.y;
    tip.z += 0.05 * contacts[i].normal.z;
    arrow.points = {contacts[i].position, tip};
    array.markers.push_back(arrow);
  }
  contacts_pub_.publish(array);
}

void CollisionCheckerNode::publish_diagnostics(const ros::WallTimerEvent&) {
  const std::string name = ros::this_node::getName();
  diagnostic_msgs::DiagnosticStatus environment;
  environment.name = name + ": environment";
  environment.hardware_id = summary_.name;
  const std::uint64_t dropped = clouds_.dropped_transform + clouds_.dropped_state;
  const std::uint64_t rejected = clouds_.rejected + clouds_.over_limit;
  const bool new_losses = dropped + rejected > clouds_lost_reported_;
  clouds_lost_reported_ = dropped + rejected;
  environment.level = new_losses ? diagnostic_msgs::DiagnosticStatus::WARN : diagnostic_msgs::DiagnosticStatus::OK;
  environment.message = new_losses ? "clouds were dropped or rejected (see the log)" : "ok";
  // The counters before the snapshot: a cloud is counted inserted only after its octree is in the
  // store, so the snapshot then holds every cloud counted (the other order once showed one cloud
  // inserted and an empty octree).
  // Each cloud's outcome is counted after it was counted received: the outcomes read first, the
  // clouds in progress (received, no outcome yet) are never negative, and 0 means every cloud
  // received has its outcome in these numbers.
  const std::uint64_t inserted = clouds_.inserted.load(), no_transform = clouds_.dropped_transform.load(),
                      no_state = clouds_.dropped_state.load(), malformed = clouds_.rejected.load(),
                      over_limit = clouds_.over_limit.load();
  const std::uint64_t received = clouds_.received.load(), superseded = clouds_.superseded.load();
  const std::uint64_t in_progress = received - (inserted + no_transform + no_state + malformed + over_limit);
  const std::shared_ptr<const Environment> env = store_->snapshot();
  environment.values = {
      kv("joint states recorded", std::to_string(joints_->recorded())),
      kv("clouds received", std::to_string(received)),
      kv("clouds inserted", std::to_string(inserted)),
      kv("clouds in progress", std::to_string(in_progress)),
      kv("clouds superseded (a newer one came while busy)", std::to_string(superseded)),
      kv("clouds dropped (no transform)", std::to_string(no_transform)),
      kv("clouds dropped (no joint state at the stamp)", std::to_string(no_state)),
      kv("clouds rejected (malformed)", std::to_string(malformed)),
      kv("clouds rejected (over ~max_cloud_points)", std::to_string(over_limit)),
      kv("points received", std::to_string(clouds_.points.load())),
      kv("points skipped (NaN or Inf)", std::to_string(clouds_.skipped_invalid.load())),
      kv("points skipped (outside the octree)", std::to_string(clouds_.skipped_outside.load())),
      kv("points skipped (outside the workspace)", std::to_string(clouds_.skipped_workspace.load())),
      kv("points on the robot", std::to_string(clouds_.on_robot.load())),
      kv("points in the robot's shadow", std::to_string(clouds_.shadowed.load())),
      kv("points on known objects", std::to_string(clouds_.on_objects.load())),
      kv("rays with no return cast", std::to_string(clouds_.no_return.load())),
      kv("pixels with no return and no camera model", std::to_string(clouds_.no_return_unplaced.load())),
      kv("last insertion (ms)", ms(clouds_.last_insert_seconds.load())),
      kv("distance fields updated in place", std::to_string(clouds_.fields_in_place.load())),
      kv("distance fields copied (every older one held)", std::to_string(clouds_.fields_copied.load())),
      kv("distance fields built", std::to_string(clouds_.fields_built.load())),
      kv("octree nodes", std::to_string(env->octree().node_count())),
      kv("octree memory (bytes)", std::to_string(env->octree().memory_bytes())),
      kv("octree resolution (m)", std::to_string(env->octree().resolution())),
      kv("collision objects", std::to_string(env->objects().size())),
      kv("pinned world versions", std::to_string(store_->pins(std::chrono::steady_clock::now()))),
      kv("pinned worlds' memory beyond the current map (bytes)", std::to_string(store_->pinned_extra_bytes())),
      kv("attached objects", std::to_string(env->attached().size())),
      kv("attached objects' proxy levels", env->attached().empty()            ? std::string("none attached")
                                           : checkers_->carried_levels_built(*env) ? std::string("built")
                                                                                   : std::string("building")),
  };
  diagnostic_msgs::DiagnosticStatus queries;
  queries.name = name + ": queries";
  queries.hardware_id = summary_.name;
  queries.level = diagnostic_msgs::DiagnosticStatus::OK;
  queries.message = "ok";
  std::ostringstream levels;
  const std::shared_ptr<const CollisionChecker> checker = this->checker();  // alive through the loop
  for (const ProxyLevel& level : checker->accelerators().proxy_levels()) {
    levels << (levels.tellp() > 0 ? " " : "") << level.level;
  }
  queries.values.push_back(kv("proxy levels ready (m)", levels.str()));
  // (query/motion_calibration.h: timed when the levels were built; 0 before two are.)
  std::ostringstream growth;
  growth << checker->accelerators().pair_exact_growth();
  queries.values.push_back(kv("exact motions: self pairs' distance from growth (m)", growth.str()));
  queries.values.push_back(kv("states checked", std::to_string(states_checked_.load())));
  for (const auto& [service, stats] : latency_) {
    const LatencyStats::Summary s = stats.summary();
    queries.values.push_back(kv(service + " requests", std::to_string(s.requests)));
    queries.values.push_back(kv(service + " errors", std::to_string(s.errors)));
    queries.values.push_back(kv(service + " in progress", std::to_string(s.in_progress)));
    if (s.requests == 0) continue;
    queries.values.push_back(kv(service + " p50 (ms)", ms(s.p50)));
    queries.values.push_back(kv(service + " p90 (ms)", ms(s.p90)));
    queries.values.push_back(kv(service + " p99 (ms)", ms(s.p99)));
  }
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  array.status = {environment, queries};
  diagnostics_pub_.publish(array);
}

}  // namespace bvh_collision
