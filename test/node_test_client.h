// Helpers for launch tests that talk to a running collision_checker node as a client would.
#pragma once

#include <gtest/gtest.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>
#include <ros/topic.h>

#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "bvh_collision/CheckState.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/ros/readiness.h"

namespace bvh_collision::test {

inline std::string node_service(const std::string& name, const std::string& node = "/collision_checker") {
  return node + "/" + name;
}

// A persistent connection per service and thread, made again when it broke (the node restarted):
// roscpp's one-shot calls fail now and then under load when the client sees the server close the
// connection before reading the answer (ros_comm#1976); a persistent connection is never closed
// between calls.
template <class Srv>
bool call_persistent(const std::string& service, Srv& srv) {
  thread_local std::map<std::string, ros::ServiceClient> clients;
  ros::ServiceClient& client = clients[service];
  if (!client.isValid()) client = ros::NodeHandle().serviceClient<Srv>(service, true);
  return client.call(srv);
}

// Calls a service and fails the test when the call itself fails (the node died or hung up).
template <class Srv>
Srv call(const std::string& name, const typename Srv::Request& request) {
  Srv srv;
  srv.request = request;
  EXPECT_TRUE(call_persistent(node_service(name), srv)) << "call to " << name << " failed";
  return srv;
}

// The same on another instance (e.g. "/framed/collision_checker").
template <class Srv>
Srv call_on(const std::string& node, const std::string& name, const typename Srv::Request& request) {
  Srv srv;
  srv.request = request;
  EXPECT_TRUE(call_persistent(node_service(name, node), srv)) << "call to " << node << "/" << name << " failed";
  return srv;
}

// The values of the node's diagnostics (published once a second), from the first message of that
// node within 15 s (other instances publish on /diagnostics too): every key of its statuses,
// all from one message; empty if none came.
inline std::map<std::string, std::string> diagnostics(const std::string& node = "/collision_checker") {
  std::mutex mutex;
  std::condition_variable arrived;
  std::map<std::string, std::string> values;
  bool found = false;
  ros::NodeHandle nh;
  const ros::Subscriber sub = nh.subscribe<diagnostic_msgs::DiagnosticArray>(
      "/diagnostics", 10, [&](const diagnostic_msgs::DiagnosticArray::ConstPtr& msg) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (found) return;
        for (const auto& status : msg->status) {
          if (status.name.rfind(node + ":", 0) != 0) continue;
          for (const auto& kv : status.values) values[kv.key] = kv.value;
          found = true;
        }
        if (found) arrived.notify_all();
      });
  std::unique_lock<std::mutex> lock(mutex);
  arrived.wait_for(lock, std::chrono::seconds(15), [&] { return found; });
  return found ? values : std::map<std::string, std::string>{};
}

// One value of the node's diagnostics by its key; "(missing)" if none came.
inline std::string diagnostic(const std::string& key, const std::string& node = "/collision_checker") {
  const auto values = diagnostics(node);
  const auto it = values.find(key);
  return it == values.end() ? "(missing)" : it->second;
}

// Waits until the node's diagnostics show `key` with a value for which `holds(value)` is true,
// or `seconds` pass (a deadline, generous: the condition is the event awaited); the last value.
template <class Holds>
std::string wait_for_diagnostic(const std::string& key, Holds holds, double seconds = 60.0,
                                const std::string& node = "/collision_checker") {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  std::string value = diagnostic(key, node);
  while (!holds(value) && ros::WallTime::now() < deadline && ros::ok()) value = diagnostic(key, node);
  return value;
}

// Waits until the node is ready (~ready true: its robot summary ~robot is set and every service
// is served), `seconds` at most.
inline bool wait_for_node(const std::string& node = "/collision_checker", double seconds = 60.0) {
  return wait_until_ready(node, seconds);
}

// Waits until the node has recorded a joint state (a deadline of 60 s) and returns a time no
// earlier than that state's stamp: a cloud stamped at or after it lies within the node's joint
// state history (one stamped before the first state the node holds is dropped, rightly: the
// robot's pose then is unknown; a joint state published before the node connected is lost).
inline ros::Time joint_states_from(const std::string& node = "/collision_checker") {
  wait_for_diagnostic("joint states recorded", [](const std::string& v) { return v != "(missing)" && v != "0"; }, 60.0, node);
  return ros::Time::now();
}

// What became of the clouds sent to a node, from one diagnostics message: each one sent is
// received or superseded (a newer one came while the node was busy); each one received is
// inserted, dropped or rejected with its reason, or still in progress.
struct CloudCounts {
  std::uint64_t received = 0, inserted = 0, in_progress = 0, superseded = 0;
  std::uint64_t no_transform = 0, no_state = 0, malformed = 0, over_limit = 0;
  // the distance fields the inserted clouds' maps got: made in place, copied, built
  std::uint64_t fields_in_place = 0, fields_copied = 0, fields_built = 0;
  std::uint64_t sent() const { return received + superseded; }
  std::uint64_t outcomes() const { return inserted + no_transform + no_state + malformed + over_limit; }
};

inline CloudCounts cloud_counts(const std::string& node = "/collision_checker") {
  const auto values = diagnostics(node);
  const auto number = [&](const std::string& key) -> std::uint64_t {
    const auto it = values.find(key);
    EXPECT_NE(it, values.end()) << "no diagnostic '" << key << "'";
    return it == values.end() ? 0 : std::stoull(it->second);
  };
  CloudCounts c;
  c.received = number("clouds received");
  c.inserted = number("clouds inserted");
  c.in_progress = number("clouds in progress");
  c.superseded = number("clouds superseded (a newer one came while busy)");
  c.no_transform = number("clouds dropped (no transform)");
  c.no_state = number("clouds dropped (no joint state at the stamp)");
  c.malformed = number("clouds rejected (malformed)");
  c.over_limit = number("clouds rejected (over ~max_cloud_points)");
  c.fields_in_place = number("distance fields updated in place");
  c.fields_copied = number("distance fields copied (every older one held)");
  c.fields_built = number("distance fields built");
  return c;
}

// Waits (a generous deadline) until `sent` clouds are accounted for: received or superseded, and
// none in progress. The caller checks what became of them.
inline CloudCounts wait_for_clouds(std::uint64_t sent, double seconds = 60.0, const std::string& node = "/collision_checker") {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  CloudCounts c = cloud_counts(node);
  while ((c.sent() < sent || c.in_progress > 0) && ros::WallTime::now() < deadline && ros::ok()) c = cloud_counts(node);
  EXPECT_EQ(c.sent(), sent) << "clouds sent to the node, received (" << c.received << ") or superseded (" << c.superseded << ")";
  EXPECT_EQ(c.in_progress, 0u);
  EXPECT_EQ(c.received, c.outcomes()) << "every cloud received is inserted, dropped or rejected";
  return c;
}

// The checker the node builds, built here from the same files: answers must be the same.
inline CollisionChecker library_checker(const std::string& urdf_path) {
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(urdf_path), PackageResolver::from_environment());
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  std::string srdf;
  if (ros::param::get("/robot_description_semantic", srdf) && !srdf.empty()) {
    apply_srdf(parse_srdf(srdf, &model), model, acm);
  }
  return CollisionChecker(std::move(model), std::move(acm));
}

inline sensor_msgs::JointState joint_state(const std::vector<std::string>& names, const std::vector<double>& values) {
  sensor_msgs::JointState s;
  s.name = names;
  s.position = values;
  return s;
}

inline CheckState::Request state_request(const CollisionChecker& checker, const std::vector<double>& values,
                                         std::uint8_t checks = 0) {
  CheckState::Request r;
  r.state = joint_state(checker.model().variable_names(), values);
  r.checks = checks;
  r.tolerance = 0.0;
  return r;
}

inline geometry_msgs::Pose pose_at(const Vec3& position) {
  geometry_msgs::Pose p;
  p.position.x = position.x(), p.position.y = position.y(), p.position.z = position.z();
  p.orientation.w = 1.0;
  return p;
}

// A shape_msgs primitive: `type` (SolidPrimitive::BOX...) with its dimensions in the message's order.
inline shape_msgs::SolidPrimitive solid(std::uint8_t type, std::vector<double> dimensions) {
  shape_msgs::SolidPrimitive s;
  s.type = type;
  s.dimensions = std::move(dimensions);
  return s;
}

// An object of one primitive at the object's origin.
inline SetCollisionObject::Request primitive_object(const std::string& id, const shape_msgs::SolidPrimitive& shape,
                                                     const Vec3& centre) {
  SetCollisionObject::Request r;
  r.id = id;
  r.primitives = {shape};
  r.primitive_poses = {pose_at(Vec3::Zero())};
  r.pose = pose_at(centre);
  return r;
}

// A box object of edge lengths `size` centred at `centre` in world_frame.
inline SetCollisionObject::Request box_object(const std::string& id, const Vec3& size, const Vec3& centre) {
  SetCollisionObject::Request r;
  r.id = id;
  r.primitives = {solid(shape_msgs::SolidPrimitive::BOX, {size.x(), size.y(), size.z()})};
  r.primitive_poses = {pose_at(Vec3::Zero())};
  r.pose.position.x = centre.x();
  r.pose.position.y = centre.y();
  r.pose.position.z = centre.z();
  r.pose.orientation.w = 1.0;
  return r;
}

// The points of a box's surface (edge lengths `size`, placed at `pose`), every `step` or a little
// less along each face: what a camera's cloud of it holds.
inline std::vector<Vec3> box_surface(const Transform& pose, const Vec3& size, double step = 0.01) {
  std::vector<Vec3> out;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const int nu = int(std::ceil(size[u] / step)), nv = int(std::ceil(size[v] / step));
    for (const double side : {-0.5, 0.5}) {
      for (int i = 0; i <= nu; ++i) {
        for (int j = 0; j <= nv; ++j) {
          Vec3 p = Vec3::Zero();
          p[axis] = side * size[axis];
          p[u] = (double(i) / nu - 0.5) * size[u];
          p[v] = (double(j) / nv - 0.5) * size[v];
          out.push_back(pose * p);
        }
      }
    }
  }
  return out;
}

// Random configurations until `want(state)` holds; fails after `tries`.
template <class Want>
std::vector<double> find_configuration(const CollisionChecker& checker, std::mt19937_64& rng, Want want,
                                       int tries = 20000) {
  for (int i = 0; i < tries; ++i) {
    std::vector<double> q = random_configuration(checker.model(), rng);
    if (want(q)) return q;
  }
  ADD_FAILURE() << "no configuration found in " << tries << " tries";
  return std::vector<double>(checker.model().variable_count(), 0.0);
}

// main() of a launch test: gtest and a ROS node named `name`, with an asynchronous spinner so that
// subscriptions and tf broadcasts run while the tests wait.
inline int run_node_tests(int argc, char** argv, const char* name) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, name);
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(1);
  spinner.start();
  return RUN_ALL_TESTS();
}

}  // namespace bvh_collision::test
