// The Python module's world (python/in_process_checker.h): objects, scenes, attached objects,
// clouds, octree files and proxy levels. Each change is made on a copy of the current snapshot
// (pages and objects shared) and published whole, so a query never sees half a change.
#include <algorithm>

#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/python/in_process_checker.h"
#include "bvh_collision/session/scene_frames.h"
#include "bvh_collision/world/object_filter.h"

namespace bvh_collision {

void InProcessChecker::add_object(const std::string& id, const ObjectShape& shape, const Transform& pose) {
  CollisionObject built = make_collision_object(id, shape, pose);  // the costly part, outside the lock
  Environment next = *snapshot();
  if (next.find_attached(id) != nullptr) throw std::invalid_argument("object '" + id + "' is attached to the robot");
  next.add_object(std::move(built));
  publish(std::move(next));
}

bool InProcessChecker::remove_object(const std::string& id) {
  Environment next = *snapshot();
  const bool removed = next.remove_object_shapes(id) > 0;
  if (removed) publish(std::move(next));
  return removed;
}

std::vector<std::string> InProcessChecker::object_ids() const {
  std::vector<std::string> ids;
  const std::shared_ptr<const Environment> env = snapshot();
  for (std::size_t i = 0; i < env->objects().size(); ++i) ids.push_back(env->objects()[i].id);
  return ids;
}

Transform InProcessChecker::link_pose(int link, const double* state) const {
  std::vector<Transform> poses;
  forward_kinematics(model(), state, poses);
  return poses[static_cast<std::size_t>(link)];
}

std::vector<std::string> InProcessChecker::load_scene(const std::string& path, const double* state) {
  require_state(state, "load_scene");
  SceneFile scene = read_scene_file(path);
  place_in_world(scene, robot_scene_frames(model(), srdf_, state));
  std::vector<std::string> warnings = scene.warnings;
  Environment next = *snapshot();
  apply_scene_objects(scene, next, warnings);  // on the copy: a failure changes nothing
  publish(std::move(next));
  return warnings;
}

void InProcessChecker::attach(const std::string& id, const std::string& link, const double* state,
                              const std::vector<std::string>& touch_links) {
  require_state(state, "attach");
  const int l = model().link_index(link);
  if (l < 0) throw std::invalid_argument("no link '" + link + "' to attach '" + id + "' to");
  for (const std::string& t : touch_links) {
    if (model().link_index(t) < 0) throw std::invalid_argument("touch link '" + t + "' is not a link");
  }
  const Transform link_world = link_pose(l, state);
  Environment next = *snapshot();
  AttachedBody body{id, link, touch_links, {}};
  for (std::size_t i = 0; i < next.objects().size(); ++i) {
    const CollisionObject& o = next.objects()[i];
    if (object_name(o.id) != id) continue;
    CollisionObject held = o;
    held.pose = relative_transform(link_world, o.pose);
    held.frame = relative_transform(link_world, o.frame);
    body.shapes.push_back(std::move(held));
  }
  if (body.shapes.empty()) throw std::invalid_argument("no world object '" + id + "' to attach");
  next.remove_object_shapes(id);
  next.attach(std::move(body));
  publish(std::move(next));
}

bool InProcessChecker::detach(const std::string& id, const double* state) {
  require_state(state, "detach");
  Environment next = *snapshot();
  const AttachedBody* body = next.find_attached(id);
  if (body == nullptr) return false;
  const Transform link_world = link_pose(model().link_index(body->link), state);
  std::vector<CollisionObject> shapes = body->shapes;
  next.detach(id);
  for (CollisionObject& o : shapes) {
    o.pose = link_world * o.pose;
    o.frame = link_world * o.frame;
    next.add_object(std::move(o));
  }
  publish(std::move(next));
  return true;
}

std::vector<std::string> InProcessChecker::attached_ids() const {
  std::vector<std::string> ids;
  for (const AttachedBody& b : snapshot()->attached()) ids.push_back(b.id);
  return ids;
}

ScanStats InProcessChecker::insert_cloud(const std::vector<ScanPoint>& points, const ScanPoint& origin, const double* state,
                                         double max_range, double self_filter_padding) {
  if (!origin.allFinite()) throw std::invalid_argument("insert_cloud: the sensor origin is not finite");
  if (!(self_filter_padding >= 0.0) || !std::isfinite(self_filter_padding)) {
    throw std::invalid_argument("insert_cloud: self_filter_padding must be a finite number >= 0");
  }
  check_limit("a cloud with its points", static_cast<double>(points.size()), checker()->collision_model().limits().cloud_points,
              "max_cloud_points");
  const std::shared_ptr<const Environment> current = snapshot();
  FilteredScan filtered;
  if (state != nullptr) {
    require_state(state, "insert_cloud");
    filtered = carrying(*current)->filter_scan(state, points, origin, self_filter_padding);
  } else {
    filtered.obstacles = points;
  }
  filter_objects(current->objects(), origin, self_filter_padding, filtered);
  Environment next = *current;
  ScanOptions options;
  options.max_range = max_range;
  options.limits = checker()->collision_model().limits();
  const std::uint64_t from = next.octree().revision();
  ScanStats stats = insert_scan(next.octree(), filtered.obstacles, filtered.clear_only, origin, options);
  next.note_octree_changes(from, std::vector<OctreeKey>(stats.flipped));
  checker()->prepare_distance_field(next);  // kept with the snapshot, as the node's scan path does
  publish(std::move(next));
  return stats;
}

void InProcessChecker::load_octree(const std::string& path) {
  Octree tree = bvh_collision::load_octree(path);
  Environment next = *snapshot();
  if (tree.resolution() != next.octree().resolution()) {
    Environment fresh(tree.resolution());
    for (std::size_t i = 0; i < next.objects().size(); ++i) fresh.add_object(next.objects()[i]);
    for (const AttachedBody& b : next.attached()) fresh.attach(b);
    fresh.set_allowed_collisions(next.allowed_collisions());
    next = std::move(fresh);
  }
  next.octree() = std::move(tree);
  if (!next.octree().empty()) checker()->prepare_distance_field(next);
  publish(std::move(next));
}

void InProcessChecker::save_octree(const std::string& path) const { bvh_collision::save_octree(snapshot()->octree(), path); }

void InProcessChecker::clear_octree() {
  Environment next = *snapshot();
  next.octree().clear();
  publish(std::move(next));
}

std::size_t InProcessChecker::occupied_voxels() const {
  const std::shared_ptr<const Environment> env = snapshot();
  std::size_t n = 0;
  for (const Octree::Leaf& leaf : env->octree().leaves()) n += env->octree().occupied(leaf.log_odds);
  return n;
}

double InProcessChecker::octree_resolution() const { return snapshot()->octree().resolution(); }

void InProcessChecker::add_proxy_level(double level) {
  auto next = std::make_shared<const CollisionChecker>(checker()->with_proxy_level(level));
  std::lock_guard<std::mutex> lock(mutex_);
  checker_ = std::move(next);
  carrying_.reset();
  scene_.reset();
}

std::vector<double> InProcessChecker::proxy_levels() const {
  std::vector<double> levels;
  for (const auto& level : checker()->accelerators().proxy_levels()) levels.push_back(level.level);
  return levels;
}

}  // namespace bvh_collision
