// demo_client: calls every service of a running collision_checker on the demo robot (make demo)
// and prints what it asked, what came back, and how long the round trip took.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <ros/ros.h>
#include <std_srvs/Empty.h>

#include "bvh_collision/CastRay.h"
#include "bvh_collision/CheckMotion.h"
#include "bvh_collision/CheckState.h"
#include "bvh_collision/CheckStates.h"
#include "bvh_collision/ClearBox.h"
#include "bvh_collision/LoadScene.h"
#include "bvh_collision/RemoveCollisionObject.h"
#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/SaveScene.h"
#include "bvh_collision/SetCollisionObject.h"
#include "bvh_collision/ros/readiness.h"

namespace {

using namespace bvh_collision;

const std::vector<std::string> kArm = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};

// Calls a service; returns the round trip in microseconds (negative when the call failed).
template <class Srv>
double timed_call(const std::string& name, Srv& srv) {
  const auto start = std::chrono::steady_clock::now();
  const bool ok = ros::service::call("/collision_checker/" + name, srv);
  const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
  return ok ? us : -1.0;
}

void heading(const char* service, const std::string& asked) { std::printf("\n%s: %s\n", service, asked.c_str()); }

std::string joints(const std::vector<double>& q) {
  std::string s = "[";
  for (std::size_t i = 0; i < q.size(); ++i) s += (i ? ", " : "") + std::to_string(q[i]).substr(0, 5);
  return s + "]";
}

void check_state(const std::string& what, const std::vector<double>& q, std::uint8_t checks, std::uint32_t contacts) {
  CheckState srv;
  srv.request.state.name = std::vector<std::string>(kArm.begin(), kArm.begin() + q.size());
  srv.request.state.position = q;
  srv.request.checks = checks;
  srv.request.max_contacts = contacts;
  srv.request.distance = contacts == 0;
  srv.request.tolerance = -1.0;
  heading("check_state", what + ", joints " + joints(q) + (checks == 1 ? ", SELF" : checks == 2 ? ", ENVIRONMENT" : ", both"));
  const double us = timed_call("check_state", srv);
  const auto& r = srv.response;
  if (!r.error.empty()) {
    std::printf("  -> error: %s  (%.0f us)\n", r.error.c_str(), us);
    return;
  }
  std::printf("  -> %s (self %s, environment %s)", r.valid ? "FREE" : "IN COLLISION", r.self_collision ? "yes" : "no",
              r.environment_collision ? "yes" : "no");
  if (!std::isnan(r.min_distance) && r.closest_pair.size() == 2) {
    std::printf(", min distance %.4f m between %s and %s", r.min_distance, r.closest_pair[0].c_str(),
                r.closest_pair[1].c_str());
  }
  std::printf("  (%.0f us)\n", us);
  for (const Contact& c : r.contacts) {
    std::printf("     contact %s / %s at (%.3f, %.3f, %.3f), depth %.4f m\n", c.body_a.c_str(), c.body_b.c_str(),
                c.position.x, c.position.y, c.position.z, c.depth);
  }
  if (!r.warning.empty()) std::printf("     warning: %s\n", r.warning.c_str());
}

// A grid over joint2 x joint3 in one check_states call; returns the first self-colliding row.
std::vector<double> batch() {
  CheckStates srv;
  srv.request.joint_names = {"joint2", "joint3"};
  const int n = 60;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      srv.request.positions.push_back(-2.0 + 4.0 * i / (n - 1));
      srv.request.positions.push_back(-2.6 + 5.2 * j / (n - 1));
    }
  }
  srv.request.checks = CheckStates::Request::SELF;
  srv.request.tolerance = -1.0;
  heading("check_states", "a 60 x 60 grid over joint2 and joint3 (3600 configurations), SELF");
  const double us = timed_call("check_states", srv);
  std::size_t free = 0;
  std::vector<double> first_hit;
  for (std::size_t r = 0; r < srv.response.valid.size(); ++r) {
    free += srv.response.valid[r];
    if (!srv.response.valid[r] && first_hit.empty()) {
      first_hit = {0.0, srv.request.positions[2 * r], srv.request.positions[2 * r + 1]};
    }
  }
  std::printf("  -> %zu free, %zu self-colliding  (%.0f us, %.2f us per configuration)%s%s\n", free,
              srv.response.valid.size() - free, us, us / 3600.0, srv.response.error.empty() ? "" : " error: ",
              srv.response.error.c_str());
  return first_hit;
}

void check_motion(double resolution) {
  CheckMotion srv;
  srv.request.joint_names = {"joint1", "joint2"};
  srv.request.start = {-0.6, 1.0};
  srv.request.goal = {1.6, 1.0};
  srv.request.resolution = resolution;
  heading("check_motion", "joint1 from -0.6 to 1.6 rad with joint2 at 1.0 (sweeping past the pillar), resolution " +
                              (resolution > 0 ? std::to_string(resolution).substr(0, 4) + " rad" : "0 (certified)"));
  const double us = timed_call("check_motion", srv);
  std::printf("  -> %s, last valid fraction %.3f, %u states checked  (%.0f us)%s%s\n",
              srv.response.valid ? "FREE" : "COLLIDES", srv.response.last_valid_fraction, srv.response.states_checked,
              us, srv.response.error.empty() ? "" : " error: ", srv.response.error.c_str());
}

void cast_ray() {
  CastRay srv;
  srv.request.origin.x = 1.2;
  srv.request.origin.z = 1.0;
  srv.request.direction.x = 0.45 - 1.2;
  srv.request.direction.y = 0.35;
  srv.request.direction.z = 0.6 - 1.0;
  heading("cast_ray", "from the camera (1.2, 0, 1.0) towards the pillar");
  const double us = timed_call("cast_ray", srv);
  const auto& r = srv.response;
  if (r.hit) {
    std::printf("  -> hit '%s' at (%.3f, %.3f, %.3f), %.3f m away  (%.0f us)\n", r.body.c_str(), r.point.x, r.point.y,
                r.point.z, r.distance, us);
  } else {
    std::printf("  -> nothing  (%.0f us)%s\n", us, r.error.c_str());
  }
}

template <class Srv>
void simple(const char* service, const std::string& asked, Srv& srv) {
  heading(service, asked);
  const double us = timed_call(service, srv);
  std::printf("  -> %s  (%.0f us)\n", srv.response.error.empty() ? "done" : ("error: " + srv.response.error).c_str(), us);
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "demo_client");
  ros::NodeHandle nh;
  if (!bvh_collision::wait_until_ready("/collision_checker", 60.0)) return 1;
  const std::vector<double> reach = {0.66, 1.0};
  // The scene publisher's first cloud: wait until the pillar is in the octree.
  for (int i = 0; i < 100; ++i) {
    CheckState probe;
    probe.request.state.name = {"joint1", "joint2"};
    probe.request.state.position = reach;
    probe.request.checks = CheckState::Request::ENVIRONMENT;
    if (ros::service::call("/collision_checker/check_state", probe) && probe.response.environment_collision) break;
    ros::WallDuration(0.1).sleep();
  }
  check_state("the current state (joint_states: the arm upright)", {}, 0, 0);
  check_state("leaning into the pillar seen by the camera", reach, 0, 3);
  const std::vector<double> folded = batch();
  if (!folded.empty()) check_state("the first self-colliding configuration of the grid", folded, 1, 3);
  check_motion(0.5);
  check_motion(0.0);
  cast_ray();

  SetCollisionObject box;
  box.request.id = "table";
  box.request.primitives.resize(1);
  box.request.primitives[0].type = shape_msgs::SolidPrimitive::BOX;
  box.request.primitives[0].dimensions = {0.6, 1.0, 0.04};
  box.request.primitive_poses.resize(1);
  box.request.primitive_poses[0].orientation.w = 1.0;
  box.request.pose.position.x = -0.6;
  box.request.pose.position.z = 0.5;
  box.request.pose.orientation.w = 1.0;
  simple("set_collision_object", "a 0.6 x 1.0 x 0.04 m table 'table' behind the robot at z = 0.5", box);
  check_state("leaning back onto the table", {0.0, -1.2}, 2, 1);
  SaveScene save_scene;
  save_scene.request.path = "/tmp/bvh_collision_demo.scene";
  save_scene.request.name = "demo table";
  simple("save_scene", save_scene.request.path + " (MoveIt .scene text: the table)", save_scene);
  RemoveCollisionObject remove;
  remove.request.id = "table";
  simple("remove_collision_object", "'table'", remove);
  check_state("leaning back again", {0.0, -1.2}, 2, 0);
  LoadScene load_scene;
  load_scene.request.path = save_scene.request.path;
  load_scene.request.merge = true;
  simple("load_scene", load_scene.request.path + ", merged with what is there", load_scene);
  check_state("leaning back onto the table read back", {0.0, -1.2}, 2, 1);
  simple("remove_collision_object", "'table'", remove);

  ClearBox clear;
  clear.request.min.x = 0.3, clear.request.min.y = 0.2, clear.request.min.z = 0.0;
  clear.request.max.x = 0.6, clear.request.max.y = 0.5, clear.request.max.z = 1.0;
  simple("clear_box", "the pillar's box (it comes back with the next cloud)", clear);
  check_state("leaning into where the pillar was", reach, 2, 0);

  SaveOctree save;
  save.request.path = "/tmp/bvh_collision_demo.bt";
  simple("save_octree", save.request.path, save);
  std_srvs::Empty empty;
  heading("clear_environment", "the octree and every object");
  const double clear_us = timed_call("clear_environment", empty);
  std::printf("  -> %s  (%.0f us)\n", clear_us >= 0 ? "done" : "failed", clear_us);
  CheckState bad;
  bad.request.state.name = {"elbow"};
  bad.request.state.position = {0.0};
  heading("check_state", "joint 'elbow' = 0 (bad input)");
  timed_call("check_state", bad);
  std::printf("  -> error: %s\n", bad.response.error.c_str());
  return 0;
}
