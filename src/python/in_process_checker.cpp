// The Python module's checker (python/in_process_checker.h): loading, the world, the queries.
#include "bvh_collision/python/in_process_checker.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/robot/package_resolver.h"
#include "bvh_collision/robot/robot_description.h"
#include "bvh_collision/world/object_filter.h"

namespace bvh_collision {
namespace {

// XML text as given, or the file a path names.
std::string xml_or_file(const std::string& text, const char* what) {
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos || text[first] == '<') return text;
  return read_description_file(what, text);
}

PackageResolver resolver(const std::vector<std::string>& paths) {
  std::vector<std::string> roots = paths;
  if (const char* env = std::getenv("ROS_PACKAGE_PATH")) {
    for (const std::string& p : split_path_list(env)) roots.push_back(p);
  }
  const char* prefixes = std::getenv("CMAKE_PREFIX_PATH");
  return PackageResolver(roots, split_path_list(prefixes ? prefixes : ""));
}

std::shared_ptr<const CollisionChecker> load(const std::string& urdf, const std::string& srdf, const InProcessOptions& o) {
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(xml_or_file(urdf, "URDF")), resolver(o.package_paths));
  if (!has_collision_geometry(model)) throw std::invalid_argument(no_collision_geometry_error(model));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  if (!srdf.empty()) apply_srdf(parse_srdf(srdf, &model), model, acm);
  CheckerOptions options;
  options.padding = o.padding;
  options.proxy_levels = o.proxy_levels;
  options.proxy_cache = o.proxy_cache;
  return std::make_shared<const CollisionChecker>(std::move(model), std::move(acm), options);
}

void require_tolerance(double tolerance) {
  if (!std::isfinite(tolerance) || tolerance < 0.0) {
    throw std::invalid_argument("tolerance must be a finite number >= 0, got " + std::to_string(tolerance));
  }
}

}  // namespace

InProcessChecker::InProcessChecker(const std::string& urdf, const std::string& srdf, const InProcessOptions& options)
    : srdf_(srdf.empty() ? srdf : xml_or_file(srdf, "SRDF")),
      checker_(load(urdf, srdf_, options)),
      model_(&checker_->model()),
      world_(std::make_shared<const Environment>(options.octree_resolution)) {}

std::shared_ptr<const Environment> InProcessChecker::snapshot() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return world_;
}

std::shared_ptr<const CollisionChecker> InProcessChecker::carrying(const Environment& env) const {
  std::lock_guard<std::mutex> lock(mutex_);
  if (env.attached().empty()) return checker_;
  if (!carrying_ || !carrying_->carries(env)) carrying_ = std::make_shared<const CollisionChecker>(checker_->carrying(env));
  return carrying_;
}

void InProcessChecker::publish(Environment next) {
  auto shared = std::make_shared<const Environment>(std::move(next));
  std::lock_guard<std::mutex> lock(mutex_);
  world_ = std::move(shared);
}

void InProcessChecker::require_state(const double* state, const char* what) const {
  if (state == nullptr) throw std::invalid_argument(std::string(what) + ": a state is needed");
  checker()->require_finite_state(state, what);
}

void InProcessChecker::require_states(const double* states, std::size_t count, const char* what) const {
  const std::shared_ptr<const CollisionChecker> robot = checker();
  for (std::size_t i = 0; i < count; ++i) {
    const double* q = states + i * dof();
    if (std::all_of(q, q + dof(), [](double v) { return std::isfinite(v); })) continue;
    robot->require_finite_state(q, (std::string(what) + " " + std::to_string(i)).c_str());
  }
}

StatesAnswer InProcessChecker::check_states(const double* states, std::size_t count, const StatesQuery& query) const {
  require_tolerance(query.tolerance);
  require_states(states, count, "state");
  const std::shared_ptr<const Environment> env = snapshot();
  const std::shared_ptr<const CollisionChecker> robot = carrying(*env);
  StatesAnswer out;
  if (!query.distance) {
    BatchRequest request;
    request.self = query.self;
    request.environment = query.environment;
    request.tolerance = query.tolerance;
    const std::vector<char> colliding = robot->check_batch(states, count, env.get(), request);
    out.valid.resize(count);
    for (std::size_t i = 0; i < count; ++i) out.valid[i] = !colliding[i];
    return out;
  }
  out.valid.assign(count, 1);
  out.distance.assign(count, std::numeric_limits<double>::infinity());
  out.nearest_a.assign(count, "");
  out.nearest_b.assign(count, "");
  const auto& links = robot->model().links();
  ThreadPool::shared().for_each(count, 4, [&](std::size_t i) {
    const double* q = states + i * dof();
    if (query.self) {
      SelfCollisionRequest request;
      request.distance = true;
      request.tolerance = query.tolerance;
      const SelfCollisionResult r = robot->check_self(q, request);
      out.valid[i] = !r.collision;
      if (r.closest_a >= 0 && r.min_distance < out.distance[i]) {
        out.distance[i] = r.collision ? 0.0 : r.min_distance;
        out.nearest_a[i] = links[r.closest_a].name, out.nearest_b[i] = links[r.closest_b].name;
      }
    }
    if (query.environment) {
      EnvironmentRequest request;
      request.distance = true;
      request.tolerance = query.tolerance;
      const EnvironmentResult r = robot->check_environment(q, *env, request);
      out.valid[i] = out.valid[i] && !r.collision;
      if (r.closest_link >= 0 && (r.collision ? 0.0 : r.min_distance) < out.distance[i]) {
        out.distance[i] = r.collision ? 0.0 : r.min_distance;
        out.nearest_a[i] = links[r.closest_link].name;
        out.nearest_b[i] = r.closest_object.empty() ? "octree" : r.closest_object;
      }
    }
    if (!out.valid[i]) out.distance[i] = 0.0;
  });
  return out;
}

std::shared_ptr<const SceneChecker> InProcessChecker::scene(const std::shared_ptr<const Environment>& env,
                                                            const StatesQuery& query) const {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool same = scene_ && scene_->environment().same_snapshot(*env) && scene_query_.self == query.self &&
                      scene_query_.environment == query.environment && scene_query_.tolerance == query.tolerance;
    if (same) return scene_;
  }
  SceneCheckOptions options;
  options.self = query.self;
  options.environment = query.environment;
  options.tolerance = query.tolerance;
  auto prepared = std::make_shared<const SceneChecker>(*checker(), env, options);  // carries env's attached objects
  std::lock_guard<std::mutex> lock(mutex_);
  scene_ = prepared;
  scene_query_ = query;
  return prepared;
}

MotionsAnswer InProcessChecker::check_motions(const double* starts, const double* goals, std::size_t count,
                                              const StatesQuery& query) const {
  require_tolerance(query.tolerance);
  require_states(starts, count, "start");
  require_states(goals, count, "goal");
  const std::shared_ptr<const SceneChecker> prepared = scene(snapshot(), query);
  MotionsAnswer out;
  out.valid.resize(count);
  out.last_valid_fraction.resize(count);
  ThreadPool::shared().for_each(count, 1, [&](std::size_t i) {
    const MotionResult r = prepared->check_motion(starts + i * dof(), goals + i * dof(), true);
    out.valid[i] = r.valid;
    out.last_valid_fraction[i] = r.last_valid_fraction;
  });
  return out;
}

std::vector<StateContact> InProcessChecker::contacts(const double* state, bool self, bool environment) const {
  require_state(state, "contacts");
  const std::shared_ptr<const Environment> env = snapshot();
  const std::shared_ptr<const CollisionChecker> robot = carrying(*env);
  const auto& links = robot->model().links();
  std::vector<StateContact> out;
  if (self) {
    SelfCollisionRequest request;
    request.all_pairs = true;
    request.max_contacts = 1;
    const SelfCollisionResult r = robot->check_self(state, request);
    for (const LinkContact& c : r.contacts) out.push_back({links[c.link_a].name, links[c.link_b].name, true, c.contact.position});
  }
  if (environment) {
    EnvironmentRequest request;
    request.all_links = true;
    const EnvironmentResult r = robot->check_environment(state, *env, request);
    for (const EnvironmentContact& c : r.contacts) {
      out.push_back({links[c.link].name, c.object.empty() ? "octree" : c.object, false, c.position});
    }
  }
  return out;
}

RayCastResult InProcessChecker::cast_ray(const double* state, const Vec3& origin, const Vec3& direction, double max_range) const {
  require_state(state, "cast_ray");
  const std::shared_ptr<const Environment> env = snapshot();
  return carrying(*env)->cast_ray(state, *env, origin, direction, max_range);
}

}  // namespace bvh_collision
