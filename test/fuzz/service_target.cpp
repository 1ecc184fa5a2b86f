#include <ros/ros.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include "bvh_collision/ros/collision_checker_node.h"
#include "byte_reader.h"
#include "message_targets.h"

namespace bvh_collision {

// The handlers, for the service target (a friend of the node).
struct NodeFuzzAccess {
  static CollisionCheckerNode& node();
  template <class Request, class Response>
  static bool call(Request& req, Response& res) {
    CollisionCheckerNode& n = node();
    if constexpr (std::is_same_v<Request, CheckState::Request>) return n.check_state(req, res);
    if constexpr (std::is_same_v<Request, CheckStates::Request>) return n.check_states(req, res);
    if constexpr (std::is_same_v<Request, CheckMotion::Request>) return n.check_motion(req, res);
    if constexpr (std::is_same_v<Request, CheckMotions::Request>) return n.check_motions(req, res);
    if constexpr (std::is_same_v<Request, CastRay::Request>) return n.cast_ray(req, res);
    if constexpr (std::is_same_v<Request, std_srvs::Empty::Request>) return n.clear_environment(req, res);
    if constexpr (std::is_same_v<Request, ClearBox::Request>) return n.clear_box(req, res);
    if constexpr (std::is_same_v<Request, SetCollisionObject::Request>) return n.set_collision_object(req, res);
    if constexpr (std::is_same_v<Request, RemoveCollisionObject::Request>) return n.remove_collision_object(req, res);
    if constexpr (std::is_same_v<Request, SetAllowedCollisions::Request>) return n.set_allowed_collisions(req, res);
    if constexpr (std::is_same_v<Request, AttachObject::Request>) return n.attach_object(req, res);
    if constexpr (std::is_same_v<Request, DetachObject::Request>) return n.detach_object(req, res);
  }
};

CollisionCheckerNode& NodeFuzzAccess::node() {
  static std::unique_ptr<CollisionCheckerNode> node = [] {
    int argc = 1;
    char name[] = "bvh_collision_fuzz";
    char* argv[] = {name, nullptr};
    ros::init(argc, argv, "bvh_collision_fuzz", ros::init_options::AnonymousName | ros::init_options::NoSigintHandler);
    if (!ros::master::check()) throw std::runtime_error("the service target needs a ROS master (ROS_MASTER_URI)");
    const std::string ns = ros::this_node::getName();
    std::ifstream file(std::string(BVH_COLLISION_SOURCE_DIR) + "/urdf/demo_arm.urdf");
    const std::string urdf((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
    ros::param::set(ns + "/robot_description", urdf);
    ros::param::set(ns + "/checker/proxy_levels", std::vector<double>{0.02});  // one, quickly: both paths
    ros::param::set(ns + "/checker/joint_state_timeout", 0.0);  // no joint_states come here
    ros::param::set(ns + "/checker/max_motion_states", 2000);
    ros::param::set(ns + "/checker/max_batch_states", 2000);
    static ros::NodeHandle nh(ns), private_nh(ns + "/checker");
    return std::make_unique<CollisionCheckerNode>(nh, private_nh);
  }();
  return *node;
}

namespace fuzz {
namespace {

// The demo arm's names (joints, links, frames) and a few others; scripts/make_loader_corpus.py
// writes its seeds with these indices.
const std::vector<std::string> kNames = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6",
                                         "finger_joint_left", "base_link", "link3", "hand", "world", "box", "octree"};

geometry_msgs::Point point(ByteReader& in) {
  geometry_msgs::Point p;
  p.x = in.number();
  p.y = in.number();
  p.z = in.number();
  return p;
}

geometry_msgs::Pose pose(ByteReader& in) {
  geometry_msgs::Pose p;
  p.position = point(in);
  p.orientation.x = in.number();
  p.orientation.y = in.number();
  p.orientation.z = in.number();
  p.orientation.w = in.number();
  return p;
}

// A SetCollisionObject request's shapes: primitives (types 0-5: every SolidPrimitive and two
// unknown), meshes, mesh resources, each with its pose; the arrays' lengths may disagree.
void shapes(ByteReader& in, SetCollisionObject::Request& req) {
  req.primitives.resize(in.count(4));
  for (auto& s : req.primitives) {
    s.type = in.count(6);
    s.dimensions = in.numbers(4);
  }
  req.primitive_poses.resize(in.count(4));
  for (auto& p : req.primitive_poses) p = pose(in);
  req.meshes.resize(in.count(3));
  for (auto& m : req.meshes) {
    m.vertices.resize(in.count(8));
    for (auto& v : m.vertices) v = point(in);
    m.triangles.resize(in.count(12));
    for (auto& t : m.triangles) {
      for (auto& index : t.vertex_indices) index = in.byte() < 250 ? in.count(9) : in.u32();
    }
  }
  req.mesh_poses.resize(in.count(3));
  for (auto& p : req.mesh_poses) p = pose(in);
  // The last: the box's name with a NUL inside (a C string stops at it and would open box.stl).
  const std::vector<std::string> uris = {"", "package://bvh_collision/test/fuzz/meshes/box.stl", "package://nothing/x.stl",
                                         "file:///nonexistent.stl", "/etc/hostname",
                                         std::string("package://bvh_collision/test/fuzz/meshes/box.stl\0x", 51)};
  req.mesh_resources.resize(in.count(3));
  for (auto& uri : req.mesh_resources) uri = in.name(uris);
  req.mesh_resource_scales.resize(in.count(3));
  for (auto& scale : req.mesh_resource_scales) {
    scale.x = in.number();
    scale.y = in.number();
    scale.z = in.number();
  }
  req.mesh_resource_poses.resize(in.count(3));
  for (auto& p : req.mesh_resource_poses) p = pose(in);
}

// An answer is an error, or it holds what it should.
// BVH_COLLISION_REPLAY_VERBOSE=1 prints each answer's error (or "answered"), to see what a seed reaches.
template <class Response>
std::string error_problem(const Response& res) {
  if (std::getenv("BVH_COLLISION_REPLAY_VERBOSE")) std::fprintf(stderr, "  -> %s\n", res.error.empty() ? "answered" : res.error.c_str());
  if (res.error.rfind("internal error", 0) == 0) return res.error;
  return "";
}

std::string answer(ByteReader& in) {
  switch (in.count(7)) {
    case 0: {
      CheckState::Request req;
      req.state.name.resize(in.count(6));
      for (auto& n : req.state.name) n = in.name(kNames);
      req.state.position = in.numbers(7);
      req.checks = in.byte();
      req.max_contacts = in.count(5);
      req.distance = in.byte() & 1;
      req.tolerance = in.number();
      req.report_allowed = in.byte() & 1;
      CheckState::Response res;
      NodeFuzzAccess::call(req, res);
      if (res.error.empty() && req.distance && std::isnan(res.min_distance) && (req.checks & 3) != 0) {
        return "check_state answered a distance of NaN";
      }
      return error_problem(res);
    }
    case 1: {
      CheckStates::Request req;
      req.joint_names.resize(in.count(5));
      for (auto& n : req.joint_names) n = in.name(kNames);
      req.positions = in.numbers(24);
      req.checks = in.byte();
      req.tolerance = in.number();
      CheckStates::Response res;
      NodeFuzzAccess::call(req, res);
      if (res.error.empty() && !req.joint_names.empty() && res.valid.size() != req.positions.size() / req.joint_names.size()) {
        return "check_states answered another number of states than it was given";
      }
      return error_problem(res);
    }
    case 2: {
      CheckMotion::Request req;
      req.joint_names.resize(in.count(5));
      for (auto& n : req.joint_names) n = in.name(kNames);
      req.start = in.numbers(5);
      req.goal = in.numbers(5);
      req.checks = in.byte();
      req.resolution = in.number();
      CheckMotion::Response res;
      NodeFuzzAccess::call(req, res);
      if (res.error.empty() && !(res.last_valid_fraction >= 0.0 && res.last_valid_fraction <= 1.0)) {
        return "check_motion answered a last valid fraction outside [0, 1]";
      }
      if (std::string problem = error_problem(res); !problem.empty() || in.remaining() == 0) return problem;
      // Bytes left: check_motions with the same names, rows of starts and goals from the rest.
      CheckMotions::Request many;
      many.joint_names = req.joint_names;
      many.starts = in.numbers(12);
      many.goals = in.numbers(12);
      many.checks = in.byte();
      CheckMotions::Response answers;
      NodeFuzzAccess::call(many, answers);
      if (answers.error.empty()) {
        if (answers.valid.size() != answers.last_valid_fraction.size() ||
            (!many.joint_names.empty() && answers.valid.size() != many.starts.size() / many.joint_names.size())) {
          return "check_motions answered another number of motions than it was given";
        }
        for (const double f : answers.last_valid_fraction) {
          if (!(f >= 0.0 && f <= 1.0)) return "check_motions answered a last valid fraction outside [0, 1]";
        }
      }
      return error_problem(answers);
    }
    case 3: {
      CastRay::Request req;
      req.origin = point(in);
      const geometry_msgs::Point d = point(in);
      req.direction.x = d.x;
      req.direction.y = d.y;
      req.direction.z = d.z;
      req.max_range = in.number();
      CastRay::Response res;
      NodeFuzzAccess::call(req, res);
      if (res.error.empty() && res.hit && !std::isfinite(res.distance)) return "cast_ray hit at a distance that is not finite";
      return error_problem(res);
    }
    case 4: {
      std_srvs::Empty::Request req;
      std_srvs::Empty::Response res;
      NodeFuzzAccess::call(req, res);
      return "";
    }
    case 5: {
      ClearBox::Request req;
      req.min = point(in);
      req.max = point(in);
      ClearBox::Response res;
      NodeFuzzAccess::call(req, res);
      return error_problem(res);
    }
    case 6: {
      SetCollisionObject::Request req;
      req.id = in.name(kNames);
      req.pose = pose(in);
      req.frame_id = in.name(kNames);
      shapes(in, req);
      SetCollisionObject::Response res;
      NodeFuzzAccess::call(req, res);
      for (const std::string& uri : req.mesh_resources) {
        if (res.error.empty() && uri.find('\0') != std::string::npos) return "a mesh URI with a NUL inside was loaded";
      }
      if (std::string problem = error_problem(res); !problem.empty() || in.remaining() == 0) return problem;
      // Bytes left: that object (or another name) attached to a link, with its geometry or the
      // world's, then detached back or removed.
      AttachObject::Request attach;
      attach.id = in.name(kNames);
      attach.link = in.name(kNames);
      attach.touch_links.resize(in.count(2));
      for (auto& n : attach.touch_links) n = in.name(kNames);
      if (in.byte() & 1) {
        attach.frame_id = req.frame_id;
        attach.pose = req.pose;
        attach.primitives = req.primitives;
        attach.primitive_poses = req.primitive_poses;
        attach.meshes = req.meshes;
        attach.mesh_poses = req.mesh_poses;
      }
      AttachObject::Response attached;
      NodeFuzzAccess::call(attach, attached);
      if (std::string problem = error_problem(attached); !problem.empty()) return problem;
      DetachObject::Request detach;
      detach.id = in.byte() & 1 ? attach.id : in.name(kNames);
      detach.remove = in.byte() & 1;
      DetachObject::Response detached;
      NodeFuzzAccess::call(detach, detached);
      return error_problem(detached);
    }
    default: {
      RemoveCollisionObject::Request req;
      req.id = in.name(kNames);
      RemoveCollisionObject::Response res;
      NodeFuzzAccess::call(req, res);
      if (std::string problem = error_problem(res); !problem.empty() || in.remaining() == 0) return problem;
      // Bytes left: allowed collisions from them (pairs, defaults, the flags).
      SetAllowedCollisions::Request allow;
      allow.names_a.resize(in.count(3));
      for (auto& n : allow.names_a) n = in.name(kNames);
      allow.names_b.resize(in.count(3));
      for (auto& n : allow.names_b) n = in.name(kNames);
      allow.default_names.resize(in.count(3));
      for (auto& n : allow.default_names) n = in.name(kNames);
      allow.allowed = in.byte() & 1;
      allow.remove = in.byte() & 1;
      SetAllowedCollisions::Response allowed;
      NodeFuzzAccess::call(allow, allowed);
      return error_problem(allowed);
    }
  }
}

}  // namespace

std::string check_service_request(const std::uint8_t* data, std::size_t size) {
  ByteReader in(data, size);
  if (std::string problem = answer(in); !problem.empty()) return problem;
  // The node still answers: the neutral state, self only.
  CheckState::Request plain;
  plain.checks = CheckState::Request::SELF;
  CheckState::Response res;
  NodeFuzzAccess::call(plain, res);
  if (!res.error.empty()) return "after that request a plain check_state failed: " + res.error;
  return "";
}

}  // namespace fuzz
}  // namespace bvh_collision
