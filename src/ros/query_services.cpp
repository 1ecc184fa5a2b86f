// The query services: check_state, check_states, check_motion, cast_ray.
#include <cmath>
#include <limits>

#include "bvh_collision/query/allowed_contacts.h"
#include "bvh_collision/ros/collision_checker_node.h"

namespace bvh_collision {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// geometry_msgs::Point or Vector3 from a vector.
template <class Msg>
Msg xyz_msg(const Vec3& v) {
  Msg m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}
const auto point_msg = xyz_msg<geometry_msgs::Point>;
const auto vector_msg = xyz_msg<geometry_msgs::Vector3>;

struct Checks {
  bool self, environment;
};

Checks read_checks(std::uint8_t checks) {
  if (checks > 3) {
    throw RequestError("checks must be SELF (1), ENVIRONMENT (2), both (3) or 0 for both, got " +
                       std::to_string(int(checks)));
  }
  return {checks != CheckState::Request::ENVIRONMENT, checks != CheckState::Request::SELF};
}

}  // namespace

double CollisionCheckerNode::request_tolerance(double requested) const {
  if (std::isnan(requested) || std::isinf(requested)) {
    throw RequestError("tolerance must be a finite number of metres (< 0 for the node's default)");
  }
  return requested < 0.0 ? params_.tolerance : requested;
}

bool CollisionCheckerNode::check_state(CheckState::Request& req, CheckState::Response& res) {
  return serve("check_state", res, [&] { answer_check_state(req, res); });
}

void CollisionCheckerNode::answer_check_state(const CheckState::Request& req, CheckState::Response& res) {
  require_geometry();
  const Checks checks = read_checks(req.checks);
  const double tolerance = request_tolerance(req.tolerance);
  if (req.state.position.size() != req.state.name.size()) {
    throw RequestError("state has " + std::to_string(req.state.name.size()) + " joint names and " +
                       std::to_string(req.state.position.size()) + " positions");
  }
  std::vector<std::string> warnings;
  const std::vector<int> columns = joint_map_->columns(req.state.name, warnings);
  std::vector<double> state = current_state_for(columns);
  joint_map_->write(columns, req.state.position.data(), req.state.name, state, warnings);
  // Contacts are reported in world_frame; a boolean or distance self check needs no pose.
  const bool need_pose = checks.environment || req.max_contacts > 0;
  const Transform root = need_pose ? root_pose(ros::Time(0)) : Transform::Identity();
  res.min_distance = kNaN;
  // One snapshot and the checker that carries its attached objects, for the whole answer (the
  // node may swap in another: a proxy level built, an object attached).
  const EnvironmentStore::Pin world_answering = world(req.world_version);
  const std::shared_ptr<const Environment>& env = world_answering.snapshot;
  const std::shared_ptr<const CollisionChecker> checker = checker_for(env);
  if (checks.self) self_part(*checker, state.data(), req, tolerance, root, res);
  if (checks.environment) environment_part(*checker, state.data(), *env, req, tolerance, root, res);
  if (checks.environment && req.report_allowed) {
    for (const auto& [link, object] : allowed_object_contacts(*checker, state.data(), *env, root)) {
      res.allowed_links.push_back(checker->model().links()[link].name);
      res.allowed_objects.push_back(object);
    }
  }
  res.valid = !res.self_collision && !res.environment_collision;
  res.world_version = world_answering.version;
  ++states_checked_;
  res.warning = join_warnings(warnings);
  if (!res.contacts.empty()) publish_contacts(res.contacts);
}

void CollisionCheckerNode::self_part(const CollisionChecker& checker, const double* state, const CheckState::Request& req,
                                     double tolerance, const Transform& root, CheckState::Response& res) {
  SelfCollisionRequest request;
  request.tolerance = tolerance;
  request.all_pairs = req.max_contacts > 0;
  request.max_contacts = req.max_contacts;
  request.distance = req.distance;
  const SelfCollisionResult result = checker.check_self(state, request);
  const auto& links = checker.model().links();
  res.self_collision = result.collision;
  for (const LinkContact& lc : result.contacts) {
    if (res.contacts.size() >= req.max_contacts) break;
    Contact c;
    c.body_a = links[lc.link_a].name;
    c.body_b = links[lc.link_b].name;
    c.position = point_msg(root * lc.contact.position);
    c.normal = vector_msg(root.R * lc.contact.normal);
    c.depth = lc.contact.depth;
    res.contacts.push_back(c);
  }
  if (req.distance && !std::isnan(result.min_distance)) {
    res.min_distance = result.min_distance;
    res.closest_pair.clear();
    if (result.closest_a >= 0) res.closest_pair = {links[result.closest_a].name, links[result.closest_b].name};
  }
}

void CollisionCheckerNode::environment_part(const CollisionChecker& checker, const double* state, const Environment& env,
                                            const CheckState::Request& req, double tolerance, const Transform& root,
                                            CheckState::Response& res) {
  EnvironmentRequest request;
  request.tolerance = tolerance;
  request.all_links = req.max_contacts > 0;
  request.distance = req.distance;
  request.root_pose = root;
  const EnvironmentResult result = checker.check_environment(state, env, request);
  const auto& links = checker.model().links();
  res.environment_collision = result.collision;
  for (const EnvironmentContact& ec : result.contacts) {
    if (res.contacts.size() >= req.max_contacts) break;
    Contact c;
    c.body_a = links[ec.link].name;
    c.body_b = ec.object.empty() ? "octree" : ec.object;
    // For the octree the library names the voxel and a point of the link's geometry that may lie
    // a link's length away; the contact is reported on the voxel, at its point nearest to that
    // one (within a voxel of the true contact), the normal pointing from there towards the link.
    const CollisionObject* object = ec.object.empty() ? nullptr : env.find_object(ec.object);
    Vec3 position = ec.position, away = object ? Vec3(ec.position - object->pose.t) : Vec3::Zero();
    if (!object) {
      const Octree& tree = env.octree();
      const double edge = tree.cube_size(ec.voxel.depth);
      const Vec3 lo = tree.cube_min(ec.voxel.key), hi = lo + Vec3::Constant(edge);
      position = ec.position.cwiseMax(lo).cwiseMin(hi);
      away = ec.position - position;
      if (away.norm() <= 1e-12) away = ec.position - (lo + Vec3::Constant(0.5 * edge));
    }
    c.position = point_msg(position);
    c.normal = vector_msg(away.norm() > 1e-12 ? Vec3(away.normalized()) : Vec3::UnitZ());
    c.depth = 0.0;
    res.contacts.push_back(c);
  }
  if (req.distance && !std::isnan(result.min_distance) &&
      (std::isnan(res.min_distance) || result.min_distance < res.min_distance)) {
    res.min_distance = result.min_distance;
    res.closest_pair.clear();
    if (result.closest_link >= 0) {
      res.closest_pair = {links[result.closest_link].name,
                          result.closest_object.empty() ? "octree" : result.closest_object};
    }
  }
}

bool CollisionCheckerNode::check_states(CheckStates::Request& req, CheckStates::Response& res) {
  return serve("check_states", res, [&] {
    require_geometry();
    const Checks checks = read_checks(req.checks);
    const double tolerance = request_tolerance(req.tolerance);
    const std::size_t n = req.joint_names.size();
    if (n == 0) {
      if (!req.positions.empty()) throw RequestError("positions are given but joint_names is empty");
      return;
    }
    if (req.positions.size() % n != 0) {
      throw RequestError("positions holds " + std::to_string(req.positions.size()) + " values, not a multiple of " +
                         std::to_string(n) + " (the number of joint names)");
    }
    std::vector<std::string> warnings;
    const std::vector<int> columns = joint_map_->columns(req.joint_names, warnings);
    const std::vector<double> base = current_state_for(columns);
    const std::size_t rows = req.positions.size() / n, vars = base.size();
    std::vector<double> states(rows * vars);
    std::size_t rows_warned = 0;
    for (std::size_t r = 0; r < rows; ++r) {
      std::vector<double> row = base;
      std::vector<std::string> row_warnings;
      try {
        joint_map_->write(columns, &req.positions[r * n], req.joint_names, row, row_warnings);
      } catch (const RequestError& e) {
        throw RequestError("configuration " + std::to_string(r) + ": " + e.what());
      }
      std::copy(row.begin(), row.end(), states.begin() + r * vars);
      if (!row_warnings.empty() && rows_warned++ < 3) {
        warnings.push_back("configuration " + std::to_string(r) + ": " + join_warnings(row_warnings, 2));
      }
    }
    if (rows_warned > 3) warnings.push_back(std::to_string(rows_warned) + " configurations have such values");
    BatchRequest request;
    request.self = checks.self;
    request.environment = checks.environment;
    request.tolerance = tolerance;
    if (checks.environment) request.root_pose = root_pose(ros::Time(0));
    const EnvironmentStore::Pin answering = world(req.world_version);  // its attached objects count in self checks too
    const std::shared_ptr<const Environment>& env = answering.snapshot;
    const std::vector<char> colliding =
        checker_for(env)->check_batch(states.data(), rows, checks.environment ? env.get() : nullptr, request);
    states_checked_ += rows;
    res.valid.resize(rows);
    for (std::size_t r = 0; r < rows; ++r) res.valid[r] = !colliding[r];
    res.world_version = answering.version;
    res.warning = join_warnings(warnings, 4);
  });
}

bool CollisionCheckerNode::check_motion(CheckMotion::Request& req, CheckMotion::Response& res) {
  return serve("check_motion", res, [&] {
    require_geometry();
    const Checks checks = read_checks(req.checks);
    const std::size_t n = req.joint_names.size();
    if (req.start.size() != n || req.goal.size() != n) {
      throw RequestError("start has " + std::to_string(req.start.size()) + " values and goal " +
                         std::to_string(req.goal.size()) + " for " + std::to_string(n) + " joint names");
    }
    if (!std::isfinite(req.resolution) || req.resolution < 0.0) {
      throw RequestError("resolution must be 0 (certified) or a positive joint step, got " +
                         std::to_string(req.resolution));
    }
    std::vector<std::string> warnings;
    const std::vector<int> columns = joint_map_->columns(req.joint_names, warnings);
    std::vector<double> start = current_state_for(columns), goal = start;
    joint_map_->write(columns, req.start.data(), req.joint_names, start, warnings);
    joint_map_->write(columns, req.goal.data(), req.joint_names, goal, warnings);
    MotionRequest request;
    request.self = checks.self;
    request.environment = checks.environment;
    request.resolution = req.resolution;
    request.tolerance = params_.tolerance;
    if (checks.environment) request.root_pose = root_pose(ros::Time(0));
    const EnvironmentStore::Pin answering = world(req.world_version);
    const std::shared_ptr<const Environment>& env = answering.snapshot;
    const MotionResult result = req.resolution > 0.0
        ? checker_for(env)->check_motion(start.data(), goal.data(), *env, request)
        : scene_checker(env, checks.self, checks.environment, request.root_pose)->check_motion(start.data(), goal.data(), true);
    res.valid = result.valid;
    res.last_valid_fraction = result.last_valid_fraction;
    res.states_checked = static_cast<std::uint32_t>(result.states_checked);
    res.world_version = answering.version;
    states_checked_ += result.states_checked;
    if (!result.message.empty()) warnings.push_back(result.message);
    res.warning = join_warnings(warnings);
  });
}

bool CollisionCheckerNode::check_motions(CheckMotions::Request& req, CheckMotions::Response& res) {
  return serve("check_motions", res, [&] {
    require_geometry();
    const Checks checks = read_checks(req.checks);
    const std::size_t n = req.joint_names.size();
    if (n == 0) throw RequestError("joint_names is empty");
    if (req.starts.size() != req.goals.size() || req.starts.size() % n != 0) {
      throw RequestError("starts has " + std::to_string(req.starts.size()) + " values and goals " +
                         std::to_string(req.goals.size()) + ": each needs the same whole number of rows of " +
                         std::to_string(n) + " (one per joint name)");
    }
    const std::size_t rows = req.starts.size() / n;
    check_limit("a check_motions request with its motions", static_cast<double>(rows),
                checker()->collision_model().limits().batch_states, "max_batch_states");
    std::vector<std::string> warnings;
    const std::vector<int> columns = joint_map_->columns(req.joint_names, warnings);
    const std::vector<double> base = current_state_for(columns);
    const Transform root = checks.environment ? root_pose(ros::Time(0)) : Transform::Identity();
    const EnvironmentStore::Pin answering = world(req.world_version);
    const std::shared_ptr<const SceneChecker> scene = scene_checker(answering.snapshot, checks.self, checks.environment, root);
    std::vector<double> start = base, goal = base;
    res.valid.resize(rows);
    res.last_valid_fraction.resize(rows);
    std::size_t checked = 0;
    for (std::size_t r = 0; r < rows; ++r) {
      joint_map_->write(columns, req.starts.data() + r * n, req.joint_names, start, warnings);
      joint_map_->write(columns, req.goals.data() + r * n, req.joint_names, goal, warnings);
      const MotionResult result = scene->check_motion(start.data(), goal.data(), true);
      res.valid[r] = result.valid;
      res.last_valid_fraction[r] = result.last_valid_fraction;
      checked += result.states_checked;
      if (!result.message.empty()) warnings.push_back("motion " + std::to_string(r) + ": " + result.message);
    }
    res.states_checked = static_cast<std::uint32_t>(std::min<std::size_t>(checked, UINT32_MAX));
    res.world_version = answering.version;
    states_checked_ += checked;
    res.warning = join_warnings(warnings, 4);
  });
}

EnvironmentStore::Pin CollisionCheckerNode::world(std::uint64_t version) {
  if (version == 0) return store_->latest();
  try {
    return {version, store_->pinned(version, std::chrono::steady_clock::now(), "~pin_timeout (" + std::to_string(params_.pin_timeout) + " s)")};
  } catch (const PinError& e) {
    throw RequestError(std::string(e.what()) + "; pin one with pin_world");
  }
}

bool CollisionCheckerNode::pin_world(PinWorld::Request& req, PinWorld::Response& res) {
  return serve("pin_world", res, [&] {
    res.timeout = params_.pin_timeout;
    if (req.release) {
      if (!store_->release(req.version)) throw RequestError("world version " + std::to_string(req.version) + " is not pinned");
      res.version = req.version;
      return;
    }
    const auto timeout = std::chrono::duration_cast<EnvironmentStore::Clock::duration>(std::chrono::duration<double>(params_.pin_timeout));
    res.version = store_->pin(timeout, std::chrono::steady_clock::now()).version;
  });
}

bool CollisionCheckerNode::cast_ray(CastRay::Request& req, CastRay::Response& res) {
  return serve("cast_ray", res, [&] {
    if (std::isnan(req.max_range)) throw RequestError("max_range is NaN");
    const Vec3 origin(req.origin.x, req.origin.y, req.origin.z);
    const Vec3 direction(req.direction.x, req.direction.y, req.direction.z);
    const std::vector<double> state = current_state_for({});  // every link where joint_states put it
    const std::shared_ptr<const Environment> env = store_->snapshot();
    const std::shared_ptr<const CollisionChecker> checker = checker_for(env);  // a carried object is hit as a link
    const RayCastResult hit = checker->cast_ray(state.data(), *env, origin, direction, req.max_range, root_pose(ros::Time(0)));
    res.hit = hit.hit;
    if (!hit.hit) return;
    res.body = hit.link >= 0 ? checker->model().links()[hit.link].name : hit.octree ? "octree" : hit.object;
    res.point = point_msg(hit.point);
    res.distance = hit.distance;
  });
}

}  // namespace bvh_collision
