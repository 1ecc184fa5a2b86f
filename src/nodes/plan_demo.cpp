// plan_demo: plans a motion with OMPL's RRTConnect through the collision checker twice, once with
// the checker in this process (planning/ompl_validity.h, on a copy of the node's octree) and once
// through the running node's services (ros/service_validity.h), then certifies each path's
// segments with the node's check_motion and prints what each variant cost. The path's tool
// positions go out as a marker (planned_path) for rviz.
//   ~checker        the node's namespace (default /collision_checker)
//   ~group          the joints to plan for (default: every joint variable)
//   ~start, ~goal   values for ~group
//   ~planning_time  seconds per planning run (default 10)
//   ~tool_link      the link whose path is drawn (default: the last link of the chain)
//   ~seed           OMPL's random seed (default 1: the same plan each run)
#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>
#include <ros/ros.h>
#include <ros/topic.h>
#include <sensor_msgs/JointState.h>
#include <tf2_ros/transform_listener.h>
#include <unistd.h>
#include <visualization_msgs/Marker.h>

#include "bvh_collision/SaveOctree.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/package_resolver.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/ros/collision_checker_node.h"
#include "bvh_collision/ros/conversions.h"
#include "bvh_collision/ros/service_validity.h"

namespace bvh_collision {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

struct PlanRun {
  std::string name;
  bool solved = false;
  double planning_seconds = 0.0, validity_seconds = 0.0;
  std::uint64_t state_checks = 0, motion_checks = 0;
  double us_per_state = 0.0, us_per_motion = 0.0;
  std::vector<std::vector<double>> waypoints;  // group values
};

std::vector<std::vector<double>> waypoints_of(const og::PathGeometric& path, std::size_t dims) {
  std::vector<std::vector<double>> out;
  for (std::size_t i = 0; i < path.getStateCount(); ++i) {
    const double* v = path.getState(static_cast<unsigned>(i))->as<ob::RealVectorStateSpace::StateType>()->values;
    out.emplace_back(v, v + dims);
  }
  return out;
}

// One planning run: the validators on `setup`, RRTConnect, the path simplified (its shortcuts
// checked by the same motion validator). In-process (`tolerant` given), the search goes on exact
// when its tolerance has not solved it in planning::kMotionsAtTolerance motions.
PlanRun plan(const std::string& name, og::SimpleSetup& setup, planning::ValidityCounters& counters,
             const std::vector<double>& start, const std::vector<double>& goal, double seconds,
             planning::CheckerPlanningContext* tolerant = nullptr) {
  PlanRun run;
  run.name = name;
  ob::ScopedState<> a(setup.getStateSpace()), b(setup.getStateSpace());
  for (std::size_t i = 0; i < start.size(); ++i) a[i] = start[i], b[i] = goal[i];
  setup.setStartAndGoalStates(a, b);
  setup.setPlanner(std::make_shared<og::RRTConnect>(setup.getSpaceInformation()));
  setup.setup();
  counters.reset();
  counters.timed = true;  // the per-check costs this demo prints
  const auto t0 = ros::WallTime::now();
  // (The limit checked by the planner, as MoveIt gives it: solve(seconds) would check it from a
  // thread of OMPL's that wakes every millisecond, and wait up to that long to join it.)
  const ob::PlannerTerminationCondition ptc = ob::timedPlannerTerminationCondition(seconds);
  const planning::SearchOutcome search =
      tolerant ? planning::solve_tolerance_first(setup, *tolerant, ptc) : planning::SearchOutcome{setup.solve(ptc)};
  run.solved = search.status == ob::PlannerStatus::EXACT_SOLUTION;
  // A simplified path its simplifier rejects is not kept (planning::simplify_or_keep).
  if (run.solved && tolerant) planning::simplify_certified(setup, *tolerant, search);
  if (run.solved && !tolerant) planning::simplify_or_keep(setup);
  run.planning_seconds = (ros::WallTime::now() - t0).toSec();
  run.validity_seconds = counters.seconds();
  run.state_checks = counters.states;
  run.motion_checks = counters.motions;
  run.us_per_state = counters.us_per_state();
  run.us_per_motion = counters.us_per_motion();
  if (run.solved) run.waypoints = waypoints_of(setup.getSolutionPath(), start.size());
  return run;
}

// The node's octree as a file read back here: the in-process checker sees what the node sees.
std::shared_ptr<const Environment> node_environment(const std::string& checker, double resolution) {
  SaveOctree save;
  save.request.path = "/tmp/bvh_collision_plan_demo_" + std::to_string(::getpid()) + ".bt";
  // A one-shot call fails now and then under load (ros_comm#1976): nothing then, and the caller
  // asks again; an answer with an error is a real failure.
  if (!ros::service::call(checker + "/save_octree", save)) return nullptr;
  if (!save.response.error.empty()) throw std::runtime_error("save_octree failed: " + save.response.error);
  auto env = std::make_shared<Environment>(resolution);
  env->octree() = load_octree(save.request.path);
  std::remove(save.request.path.c_str());
  return env;
}

// The robot as the node models it, with the node's proxy levels (read from the node's proxy
// cache when it has built them: the planner's fast path, planning/ompl_validity.h).
CollisionChecker checker_from_parameters(const std::string& node) {
  std::string urdf, srdf;
  if (!ros::param::get("robot_description", urdf)) throw std::runtime_error("no robot_description parameter");
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(urdf), PackageResolver::from_environment());
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  if (ros::param::get("robot_description_semantic", srdf) && !srdf.empty()) apply_srdf(parse_srdf(srdf, &model), model, acm);
  const NodeParameters node_parameters = read_node_parameters(ros::NodeHandle(node));
  CheckerOptions options;
  options.proxy_levels = node_parameters.proxy_levels;
  options.proxy_cache = node_parameters.proxy_cache;
  options.padding = node_parameters.padding;
  options.link_padding = node_parameters.link_padding;
  return CollisionChecker(std::move(model), std::move(acm), options);
}

void print_header() {
  std::printf("  %-22s %-7s %10s %8s %8s %22s %12s %12s %9s\n", "variant", "result", "planning", "states", "motions",
              "time in the checks", "us a state", "us a motion", "waypoints");
}

void print_run(const PlanRun& r) {
  std::printf("  %-22s %-7s %8.3f s %8llu %8llu %11.3f s (%3.0f%%) %12.1f %12.1f %9zu\n", r.name.c_str(), r.solved ? "solved" : "FAILED",
              r.planning_seconds, static_cast<unsigned long long>(r.state_checks),
              static_cast<unsigned long long>(r.motion_checks), r.validity_seconds,
              r.planning_seconds > 0 ? 100.0 * r.validity_seconds / r.planning_seconds : 0.0, r.us_per_state, r.us_per_motion,
              r.waypoints.size());
}

}  // namespace
}  // namespace bvh_collision

namespace bvh_collision {
namespace {

std::vector<double> param_list(const ros::NodeHandle& pnh, const std::string& name) {
  std::vector<double> v;
  if (!pnh.getParam(name, v)) throw std::runtime_error("parameter ~" + name + " (a list of joint values) is not set");
  return v;
}

// The robot's current joint values for the joints outside the group (joint_states, once).
std::vector<double> current_state(const RobotModel& model) {
  std::vector<double> q(model.variable_count(), 0.0);
  const auto msg = ros::topic::waitForMessage<sensor_msgs::JointState>("joint_states", ros::Duration(5.0));
  if (!msg) return q;
  for (std::size_t i = 0; i < msg->name.size() && i < msg->position.size(); ++i) {
    const auto& names = model.variable_names();
    const auto it = std::find(names.begin(), names.end(), msg->name[i]);
    if (it != names.end()) q[it - names.begin()] = msg->position[i];
  }
  return q;
}

// world_frame -> the root link from tf (identity when they are the same frame).
Transform root_pose(const std::string& world, const std::string& root) {
  if (world.empty() || world == root) return Transform::Identity();
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  return to_transform(buffer.lookupTransform(world, root, ros::Time(0), ros::Duration(5.0)).transform);
}

// The tool's positions along the path (each segment in 20 steps), as a line for rviz.
visualization_msgs::Marker path_marker(const planning::CheckerPlanningContext& c, const PlanRun& run,
                                       const std::string& frame, int tool) {
  visualization_msgs::Marker m;
  m.header.frame_id = frame;
  m.header.stamp = ros::Time::now();
  m.ns = "planned_path";
  m.type = visualization_msgs::Marker::LINE_STRIP;
  m.pose.orientation.w = 1.0;
  m.scale.x = 0.01;
  m.color.r = 1.0, m.color.g = 1.0, m.color.b = 0.0, m.color.a = 1.0;  // yellow: no voxel has it
  ob::RealVectorStateSpace space(static_cast<unsigned>(c.group.size()));
  ob::State* s = space.allocState();
  std::vector<Transform> poses;
  for (std::size_t w = 0; w + 1 < run.waypoints.size(); ++w) {
    for (int k = 0; k <= 20; ++k) {
      double* v = s->as<ob::RealVectorStateSpace::StateType>()->values;
      for (std::size_t i = 0; i < c.group.size(); ++i) v[i] = run.waypoints[w][i] + k / 20.0 * (run.waypoints[w + 1][i] - run.waypoints[w][i]);
      const std::vector<double> q = c.full_state(s);
      forward_kinematics(c.checker.model(), q.data(), poses);
      const Vec3 p = c.root_pose * poses[tool].t;
      geometry_msgs::Point point;
      point.x = p.x(), point.y = p.y(), point.z = p.z();
      m.points.push_back(point);
    }
  }
  space.freeState(s);
  return m;
}

// Every segment of the path through the node's certified check_motions (one call); prints the result.
bool certify(const ServicePlanningContext& service, const PlanRun& run) {
  std::vector<double> starts, goals;
  for (std::size_t w = 0; w + 1 < run.waypoints.size(); ++w) {
    starts.insert(starts.end(), run.waypoints[w].begin(), run.waypoints[w].end());
    goals.insert(goals.end(), run.waypoints[w + 1].begin(), run.waypoints[w + 1].end());
  }
  const std::size_t segments = run.waypoints.empty() ? 0 : run.waypoints.size() - 1;
  const std::vector<bool> free = service.motions_valid(starts.data(), goals.data(), segments);
  bool all = run.solved;
  for (std::size_t w = 0; w < free.size(); ++w) {
    all = all && free[w];
    if (!free[w]) std::printf("    segment %zu of the %s path: COLLIDING\n", w, run.name.c_str());
  }
  std::printf("  %-22s %zu segments, each certified free by check_motions: %s\n", run.name.c_str(), segments,
              all ? "yes" : "NO");
  return all;
}

int run(ros::NodeHandle& pnh) {
  const std::string node = pnh.param<std::string>("checker", "/collision_checker");
  const double seconds = pnh.param("planning_time", 10.0);
  std::vector<std::string> names;
  pnh.getParam("group", names);
  const std::vector<double> start = param_list(pnh, "start"), goal = param_list(pnh, "goal");
  const CollisionChecker checker = checker_from_parameters(node);
  const planning::JointGroup group = planning::JointGroup::of(checker.model(), names);
  if (start.size() != group.size() || goal.size() != group.size()) {
    throw std::runtime_error("~start and ~goal need " + std::to_string(group.size()) + " values each");
  }
  auto service = std::make_shared<ServicePlanningContext>(node, group);
  // The node sees the obstacles once a cloud is in: wait for a non-empty octree (a deadline of
  // 120 s: a cloud comes within a second or two, on a busy machine too).
  std::shared_ptr<const Environment> env;
  const double resolution = ros::param::param(node + "/resolution", 0.02);
  for (int i = 0; i < 240 && ros::ok(); ++i, ros::WallDuration(0.5).sleep()) {
    env = node_environment(node, resolution);
    if (env && !env->octree().empty()) break;
  }
  if (!env || env->octree().empty()) throw std::runtime_error("the node's octree stayed empty (no obstacle cloud?)");
  const std::string world = ros::param::param<std::string>(node + "/world_frame", "");
  const RobotModel& model = checker.model();
  auto context = std::make_shared<planning::CheckerPlanningContext>(checker, env, group, current_state(model));
  context->root_pose = root_pose(world, model.links()[model.root_link()].name);
  // The snapshot prepared for planning (the octree's distance field, the object grid) before the
  // clock starts, as the node prepares its own after each map change.
  const auto prepare_start = ros::WallTime::now();
  context->scene();
  const double prepare_seconds = (ros::WallTime::now() - prepare_start).toSec();

  auto space = group.make_space();
  og::SimpleSetup in_process(space);
  in_process.setStateValidityChecker(std::make_shared<planning::CheckerStateValidityChecker>(in_process.getSpaceInformation(), context));
  in_process.getSpaceInformation()->setMotionValidator(
      std::make_shared<planning::CheckerMotionValidator>(in_process.getSpaceInformation(), context));
  og::SimpleSetup through_node(group.make_space());
  through_node.setStateValidityChecker(std::make_shared<ServiceStateValidityChecker>(through_node.getSpaceInformation(), service));
  through_node.getSpaceInformation()->setMotionValidator(
      std::make_shared<ServiceMotionValidator>(through_node.getSpaceInformation(), service));

  std::printf("plan_demo: RRTConnect for %zu joints in the node's octree (%zu nodes), up to %.0f s per run; in-process: "
              "tolerance %g m, proxy levels of %zu sizes, the snapshot prepared in %.0f ms\n",
              group.size(), env->octree().node_count(), seconds, context->tolerance,
              checker.accelerators().proxy_levels().size(), 1e3 * prepare_seconds);
  double straight = 0.0;
  const bool straight_free = service->motion_valid(start.data(), goal.data(), &straight);
  std::printf("  the straight motion from start to goal: %s\n",
              straight_free ? "free" : ("colliding (free up to " + std::to_string(straight) + " of the way)").c_str());
  print_header();
  const PlanRun local = plan("in-process", in_process, *context->counters, start, goal, seconds, context.get());
  print_run(local);
  const PlanRun remote = plan("through the services", through_node, *service->counters, start, goal, seconds);
  print_run(remote);
  const bool certified = certify(*service, local) & certify(*service, remote);

  ros::NodeHandle nh;
  ros::Publisher marker = nh.advertise<visualization_msgs::Marker>("planned_path", 1, true);
  int tool = model.link_index(pnh.param<std::string>("tool_link", ""));
  if (tool < 0) tool = static_cast<int>(model.links().size()) - 1;
  if (local.solved) marker.publish(path_marker(*context, local, world.empty() ? model.links()[model.root_link()].name : world, tool));
  const double hold = pnh.param("hold", 0.0);  // keep the latched path up for rviz this long
  if (hold > 0) ros::WallDuration(hold).sleep();
  return local.solved && remote.solved && certified ? 0 : 1;
}

}  // namespace
}  // namespace bvh_collision

int main(int argc, char** argv) {
  ros::init(argc, argv, "plan_demo");
  ros::NodeHandle pnh("~");
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  ompl::RNG::setSeed(1);  // before any sampler exists: every run of the demo draws the same samples
  try {
    return bvh_collision::run(pnh);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "plan_demo: %s\n", e.what());
    return 1;
  }
}
