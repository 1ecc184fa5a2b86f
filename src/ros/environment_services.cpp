// The environment: point clouds into the octree (through tf2 and the self filter), and the
// services that change or save it.
#include <chrono>
#include <filesystem>
#include <cmath>
#include <algorithm>
#include <map>

#include "bvh_collision/session/scan_update.h"
#include "bvh_collision/io/scene_file.h"
#include "bvh_collision/octree/octomap_bridge.h"
#include "bvh_collision/ros/collision_checker_node.h"

namespace bvh_collision {

namespace {

// Beyond the robot's reach, by this much, obstacles are ignored (docs/design.md).
constexpr double kWorkspaceMargin = 0.5;

// Removes object `id`, or every shape "id#k" of an object of several; false when there was none.
bool remove_object_shapes(Environment& env, const std::string& id) { return env.remove_object_shapes(id) > 0; }

// Shapes as scene objects: the shapes id#0, id#1, ... of an object of several back into one
// object `id` (in the order of k), the object posed at its frame and its shapes within it.
std::vector<SceneObject> objects_of(const std::vector<const CollisionObject*>& shapes) {
  std::map<std::string, std::map<std::size_t, const CollisionObject*>> parts;
  std::vector<std::string> order;  // objects in the order their first shape comes
  for (const CollisionObject* o : shapes) {
    const auto hash = o->id.rfind('#');
    const bool part = hash != std::string::npos && hash + 1 < o->id.size() &&
                      o->id.find_first_not_of("0123456789", hash + 1) == std::string::npos;
    const std::string id = part ? o->id.substr(0, hash) : o->id;
    if (parts.find(id) == parts.end()) order.push_back(id);
    parts[id][part ? std::stoul(o->id.substr(hash + 1)) : 0] = o;
  }
  std::vector<SceneObject> out;
  for (const std::string& id : order) {
    SceneObject object;
    object.id = id;
    object.pose = parts[id].begin()->second->frame;
    for (const auto& [k, shape] : parts[id]) object.shapes.push_back(SceneShape{shape->shape, relative_transform(object.pose, shape->pose)});
    out.push_back(std::move(object));
  }
  return out;
}

// The collision objects, the attached ones (in their links' frames) and the allowed-collision
// entries as a scene, posed in the world.
SceneFile scene_of(const Environment& env, const std::string& name) {
  SceneFile scene;
  scene.name = name.empty() ? "(noname)+" : name;
  std::vector<const CollisionObject*> shapes;
  for (const CollisionObject& o : env.objects()) shapes.push_back(&o);
  scene.objects = objects_of(shapes);
  for (const AttachedBody& body : env.attached()) {
    shapes.clear();
    for (const CollisionObject& o : body.shapes) shapes.push_back(&o);
    for (SceneObject& o : objects_of(shapes)) {
      o.frame_id = body.link;
      scene.attached.push_back(SceneAttachedObject{body.link, std::move(o), body.touch_links});
    }
  }
  // The allowed-collision entries (YAML keeps them; the .scene text has no place for them).
  for (const auto& [pair, allowed] : env.allowed_collisions().entries()) scene.allowed_collisions.push_back({pair.first, pair.second, allowed});
  for (const auto& [who, allowed] : env.allowed_collisions().defaults()) scene.default_allowed.emplace_back(who, allowed);
  return scene;
}

}  // namespace

// The subscription keeps one cloud (the newest) while the node inserts another: the ones it
// replaces never reach this callback, nor do those a publisher's queue dropped. Both show as a
// gap in the publisher's header.seq (roscpp and rospy number every message they send on a
// topic), so each cloud sent to the node is counted: inserted, or dropped with its reason.
void CollisionCheckerNode::count_superseded(const ros::MessageEvent<const sensor_msgs::PointCloud2>& event) {
  const std::uint32_t seq = event.getConstMessage()->header.seq;
  const auto [last, first] = last_cloud_seq_.try_emplace(event.getPublisherName(), seq);
  // A publisher's first cloud, or a restarted publisher (its numbers begin again): no gap known.
  if (!first && seq > last->second) clouds_.superseded += seq - last->second - 1;
  last->second = seq;
}

void CollisionCheckerNode::on_cloud(const ros::MessageEvent<const sensor_msgs::PointCloud2>& event) {
  // The cloud thread and its fan-outs behind the queries (~cloud_nice): set on its first cloud.
  static thread_local const bool background = [this] {
    if (!ThreadPool::lower_this_thread(params_.cloud_nice)) ROS_WARN("collision_checker: ~cloud_nice could not be applied");
    ThreadPool::use_on_this_thread(cloud_pool_.get());
    return true;
  }();
  (void)background;
  ++clouds_.received;
  count_superseded(event);
  try {
    insert_cloud(*event.getConstMessage());
  } catch (const LimitExceeded& e) {
    ++clouds_.over_limit;
    ROS_WARN_STREAM_THROTTLE(5.0, "collision_checker: cloud rejected: " << e.what());
  } catch (const RequestError& e) {
    ++clouds_.rejected;
    ROS_WARN_STREAM_THROTTLE(5.0, "collision_checker: cloud rejected: " << e.what());
  } catch (const std::exception& e) {
    ++clouds_.rejected;
    ROS_ERROR_STREAM_THROTTLE(5.0, "collision_checker: cloud insertion failed: " << e.what());
  }
}

void CollisionCheckerNode::insert_cloud(const sensor_msgs::PointCloud2& msg) {
  const auto start = std::chrono::steady_clock::now();
  if (msg.header.frame_id.empty()) throw RequestError("cloud has an empty frame_id");
  check_limit("a cloud with its points", double(msg.width) * double(msg.height), params_.limits.cloud_points,
              "max_cloud_points");
  std::vector<ScanPoint> points = cloud_points(msg);
  std::vector<ScanPoint> dark = params_.clear_no_return ? no_return_rays(msg, points) : std::vector<ScanPoint>{};
  // Where the sensor and the robot were when the cloud was taken; a transform that does not come
  // within the timeout drops the cloud (counted), rather than queueing it forever.
  Transform sensor, root;
  try {
    const ros::Duration timeout(params_.cloud_transform_timeout);
    sensor = msg.header.frame_id == params_.world_frame
                 ? Transform::Identity()
                 : to_transform(
                       tf_buffer_.lookupTransform(params_.world_frame, msg.header.frame_id, msg.header.stamp, timeout)
                           .transform);
    root = root_pose(msg.header.stamp, timeout);
  } catch (const std::exception& e) {  // tf2::TransformException or RequestError
    ++clouds_.dropped_transform;
    ROS_WARN_STREAM_THROTTLE(5.0, "collision_checker: cloud dropped: no transform from '"
                                      << msg.header.frame_id << "' at its stamp: " << e.what());
    return;
  }
  for (ScanPoint& p : points) p = (sensor.R * p.cast<double>() + sensor.t).cast<float>();
  for (ScanPoint& p : dark) p = (sensor.R * p.cast<double>() + sensor.t).cast<float>();
  const ScanPoint origin = sensor.t.cast<float>();

  ScanOptions options;
  options.max_range = params_.max_range;
  options.limits = params_.limits;
  options.clip_rays_to_workspace = params_.clear_no_return;
  const double half = checker()->reach() + kWorkspaceMargin;
  options.workspace = params_.workspace_min
                          ? ScanWorkspace{params_.workspace_min->cast<float>(), params_.workspace_max->cast<float>()}
                          : ScanWorkspace{(root.t.array() - half).matrix().cast<float>(),
                                          (root.t.array() + half).matrix().cast<float>()};
  // The robot where it was at the stamp: with the latest joint values instead, a moving arm's
  // own points stay as obstacles and real points near its present pose are dropped.
  const std::optional<std::vector<double>> at_stamp =
      state_at(msg.header.stamp, ros::WallDuration(params_.cloud_transform_timeout));
  if (!at_stamp) {
    ++clouds_.dropped_state;
    ROS_WARN_STREAM_THROTTLE(5.0, "collision_checker: cloud dropped: no joint state at its stamp "
                                      << msg.header.stamp << " (joint_state_history " << params_.joint_state_history
                                      << " s, joint_state_lead " << params_.joint_state_lead << " s)");
    return;
  }
  const std::vector<double>& state = *at_stamp;
  ScanUpdateOptions update;
  update.self_filter_padding = params_.self_filter_padding;
  update.object_padding = params_.object_padding.value_or(params_.self_filter_padding);
  update.scan = options;
  update.distance_field = params_.distance_field;
  const ScanUpdateResult result = update_scan(*store_, *checkers_, points, dark, origin, state.data(), root, update);
  const ScanStats& stats = result.stats;
  clouds_.no_return += dark.size();
  clouds_.points += stats.points;
  clouds_.skipped_invalid += stats.skipped_invalid;
  clouds_.skipped_outside += stats.skipped_outside;
  clouds_.skipped_workspace += stats.skipped_workspace;
  clouds_.on_robot += result.on_robot;
  clouds_.shadowed += result.shadowed;
  clouds_.on_objects += result.on_objects;
  if (result.field_made) {
    ++(result.field.rebuilt ? clouds_.fields_built : result.field.copied_cells > 0 ? clouds_.fields_copied : clouds_.fields_in_place);
  }
  clouds_.last_insert_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Last: diagnostics read this first, so a cloud counted inserted has its points counted and its
  // octree in the store.
  ++clouds_.inserted;
}

std::vector<ScanPoint> CollisionCheckerNode::no_return_rays(const sensor_msgs::PointCloud2& msg,
                                                            const std::vector<ScanPoint>& points) {
  if (msg.height <= 1) return {};  // unorganized: a NaN point has no direction
  const auto agrees = [&](const PinholeCamera& c) { return pinhole_agrees(points, msg.width, msg.height, c); };
  const auto key = std::make_tuple(msg.header.frame_id, msg.width, msg.height);
  // In order: the CameraInfo of this camera (frame and size), ~camera_intrinsics, a model fitted
  // to this cloud, the last one fitted to this camera's clouds; each only if the cloud's points
  // agree with it (a model that is not this camera's would clear the wrong space).
  std::optional<PinholeCamera> camera;
  std::lock_guard<std::mutex> lock(camera_mutex_);
  if (camera_info_ && camera_info_->frame == msg.header.frame_id && camera_info_->width == msg.width &&
      camera_info_->height == msg.height && agrees(camera_info_->camera)) {
    camera = camera_info_->camera;
  } else if (params_.camera_intrinsics && agrees(*params_.camera_intrinsics)) {
    camera = params_.camera_intrinsics;
  } else if ((camera = fit_pinhole(points, msg.width, msg.height))) {
    fitted_cameras_[key] = *camera;
  } else if (const auto it = fitted_cameras_.find(key); it != fitted_cameras_.end() && agrees(it->second)) {
    camera = it->second;
  }
  if (!camera) {
    const auto dark = static_cast<std::size_t>(
        std::count_if(points.begin(), points.end(), [](const ScanPoint& p) { return !p.allFinite(); }));
    clouds_.no_return_unplaced += dark;
    if (dark > 0) {
      ROS_WARN_STREAM_THROTTLE(5.0, "collision_checker: " << dark << " NaN pixels of an organized cloud in '"
                                        << msg.header.frame_id << "' clear nothing: no CameraInfo of that camera on "
                                        << "~camera_info, no ~camera_intrinsics that its points agree with, and they "
                                        << "fit no pinhole camera");
    }
    return {};
  }
  return no_return_ends(points, msg.width, msg.height, *camera, params_.max_range);
}

void CollisionCheckerNode::on_camera_info(const sensor_msgs::CameraInfo& msg) {
  const PinholeCamera camera{msg.K[0], msg.K[4], msg.K[2], msg.K[5]};
  if (!camera.valid()) {
    ROS_WARN_STREAM_THROTTLE(5.0, "collision_checker: CameraInfo on ~camera_info has no usable K (fx, fy zero); ignored");
    return;
  }
  std::lock_guard<std::mutex> lock(camera_mutex_);
  camera_info_ = CameraModel{camera, msg.header.frame_id, msg.width, msg.height};
}

bool CollisionCheckerNode::clear_environment(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  const auto start = std::chrono::steady_clock::now();
  latency_.at("clear_environment").begin();
  store_->modify([](Environment& env) {
    env.octree().clear();
    env.clear_objects();
  });
  latency_.at("clear_environment")
      .record(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), false);
  return true;
}

bool CollisionCheckerNode::clear_box(ClearBox::Request& req, ClearBox::Response& res) {
  return serve("clear_box", res, [&] {
    const Vec3 lo(req.min.x, req.min.y, req.min.z), hi(req.max.x, req.max.y, req.max.z);
    if (!lo.allFinite() || !hi.allFinite()) throw RequestError("box corners must be finite");
    if ((lo.array() > hi.array()).any()) throw RequestError("box min exceeds max on some axis");
    store_->modify([&](Environment& env) { env.octree().clear_box(lo, hi); });
  });
}

bool CollisionCheckerNode::set_collision_object(SetCollisionObject::Request& req, SetCollisionObject::Response& res) {
  return serve("set_collision_object", res, [&] {
    if (req.id.empty()) throw RequestError("collision object id is empty");
    if (req.id == "octree") throw RequestError("'octree' is reserved: it names the obstacle octree in contacts");
    if (const std::string problem = object_id_problem(req.id); !problem.empty()) throw RequestError("collision object " + problem);
    if (store_->snapshot()->find_attached(req.id) != nullptr) {
      throw RequestError("object '" + req.id + "' is attached to a link: detach_object it first");
    }
    const Transform pose = frame_to_world(req.frame_id) * to_transform(req.pose);
    // Meshes are read before the environment is locked: a slow file delays no other change.
    const std::vector<PlacedShape> shapes = object_shapes(req, resolver_);
    double triangles = 0.0;
    for (const PlacedShape& s : shapes) triangles += static_cast<double>(s.shape.triangle_count());
    check_limit("collision object '" + req.id + "' with its triangles", triangles, params_.limits.object_triangles,
                "max_object_triangles");
    // The hierarchies and hulls too: the store's write lock is held only to swap the objects in.
    std::vector<CollisionObject> parts;
    for (std::size_t k = 0; k < shapes.size(); ++k) {
      const std::string name = shapes.size() == 1 ? req.id : req.id + "#" + std::to_string(k);
      parts.push_back(make_collision_object(name, shapes[k].shape, pose * shapes[k].pose));
      parts.back().frame = pose;
    }
    store_->modify([&](Environment& env) {
      if (env.find_attached(req.id) != nullptr) throw RequestError("object '" + req.id + "' is attached to a link: detach_object it first");
      remove_object_shapes(env, req.id);  // a replaced object may have had more or fewer shapes
      for (CollisionObject& part : parts) env.add_object(std::move(part));
    });
  });
}

bool CollisionCheckerNode::remove_collision_object(RemoveCollisionObject::Request& req,
                                                   RemoveCollisionObject::Response& res) {
  return serve("remove_collision_object", res, [&] {
    if (const std::string problem = object_id_problem(req.id); !problem.empty()) throw RequestError("collision object " + problem);
    // Thrown inside the change: the store then publishes nothing (an unknown id is no new snapshot).
    store_->modify([&](Environment& env) {
      if (!remove_object_shapes(env, req.id)) throw RequestError("no collision object with id '" + req.id + "'");
    });
  });
}

bool CollisionCheckerNode::save_octree(SaveOctree::Request& req, SaveOctree::Response& res) {
  return serve("save_octree", res, [&] {
    if (req.path.empty()) throw RequestError("path is empty");
    try {
      bvh_collision::save_octree(store_->snapshot()->octree(), req.path);
    } catch (const std::runtime_error& e) {
      throw RequestError(e.what());
    }
  });
}

bool CollisionCheckerNode::load_scene(LoadScene::Request& req, LoadScene::Response& res) {
  return serve("load_scene", res, [&] {
    if (req.path.empty()) throw RequestError("path is empty");
    // Read, placed and checked before the environment is locked; built in the change, which
    // publishes nothing when it throws (a refused file changes nothing).
    SceneFile scene = read_scene_for_node(req.path);
    const RobotModel& model = checker()->model();
    std::size_t link_pairs = 0;
    NamedAllowedCollisions entries;
    for (const AllowedCollision& e : scene.allowed_collisions) {
      if (model.link_index(e.a) >= 0 && model.link_index(e.b) >= 0) ++link_pairs;
      else entries.set_entry(e.a, e.b, e.allowed);
    }
    std::vector<std::string> warnings = scene.warnings;
    const std::shared_ptr<const CollisionChecker> base = checker();
    store_->modify([&](Environment& env) {
      for (const SceneObject& o : scene.objects) {
        if (env.find_attached(o.id) != nullptr) throw RequestError(req.path + ": object '" + o.id + "' is attached to a link: detach_object it first");
      }
      if (!req.merge && !scene.is_diff) env.clear_objects();
      try {
        apply_scene_objects(scene, env, warnings);
      } catch (const SceneFileError& e) {
        throw RequestError(req.path + ": " + e.what());
      }
      attach_scene_objects(scene, env, req.path);
      NamedAllowedCollisions acm = req.merge || scene.is_diff ? env.allowed_collisions() : NamedAllowedCollisions{};
      for (const auto& [pair, allowed] : entries.entries()) acm.set_entry(pair.first, pair.second, allowed);
      for (const auto& [name, allowed] : scene.default_allowed) acm.set_default(name, allowed);
      env.set_allowed_collisions(std::move(acm));
      if (!scene.attached.empty()) {
        try {
          base->carrying(env, false);
        } catch (const std::invalid_argument& e) {
          throw RequestError(e.what());
        }
      }
    });
    if (!scene.attached.empty()) checker_for(store_->snapshot());  // carried at once, its proxy levels started
    res.name = scene.name;
    res.objects = static_cast<std::uint32_t>(scene.objects.size() + scene.attached.size());
    res.shapes = static_cast<std::uint32_t>(scene.shape_count());
    if (!scene.joint_values.empty()) warnings.push_back("its robot state is not applied (" + std::to_string(scene.joint_values.size()) + " joints: the node's come from joint_states)");
    if (link_pairs > 0) warnings.push_back("its allowed-collision entries for " + std::to_string(link_pairs) + " pairs of links are not applied (the robot's SRDF decides those)");
    for (std::size_t k = 0; k < warnings.size(); ++k) res.warning += (k ? "; " : "") + warnings[k];
  });
}

// The scene file read and placed in world_frame (its frames through tf2: robot links, or any
// frame tf2 resolves now), its objects checked against the node's rules and limits.
SceneFile CollisionCheckerNode::read_scene_for_node(const std::string& path) const {
  SceneFile scene;
  try {
    scene = read_scene_file(path);
    place_in_world(scene, [&](const std::string& frame) -> std::optional<Transform> {
      try {
        return frame_to_world(frame);
      } catch (const RequestError&) {
        return std::nullopt;
      }
    });
  } catch (const SceneFileError& e) {
    throw RequestError(e.what());
  }
  const RobotModel& model = checker()->model();
  auto limit = [&](const SceneObject& o, const char* kind) {
    double triangles = 0.0;
    for (const SceneShape& s : o.shapes) triangles += static_cast<double>(s.shape.triangle_count());
    check_limit(std::string(kind) + " '" + o.id + "' with its triangles", triangles, params_.limits.object_triangles, "max_object_triangles");
  };
  for (const SceneObject& o : scene.objects) {
    if (o.id == "octree") throw RequestError(path + ": object id 'octree' is reserved: it names the obstacle octree in contacts");
    limit(o, "collision object");
  }
  for (const SceneAttachedObject& a : scene.attached) {
    if (a.object.id == "octree" || model.link_index(a.object.id) >= 0) throw RequestError(path + ": attached object id '" + a.object.id + "' is reserved or a link's name");
    if (model.link_index(a.link) < 0) throw RequestError(path + ": no link '" + a.link + "' to attach '" + a.object.id + "' to");
    for (const std::string& t : a.touch_links) {
      if (model.link_index(t) < 0) throw RequestError(path + ": touch link '" + t + "' of '" + a.object.id + "' is not a link");
    }
    limit(a.object, "attached object");
  }
  return scene;
}

// The scene's attached objects hung from their links (in the link's frame): given by shapes, or
// the world's object of that id moved to the robot (MoveIt's attach of an existing object).
void CollisionCheckerNode::attach_scene_objects(const SceneFile& scene, Environment& env, const std::string& path) const {
  for (const SceneAttachedObject& a : scene.attached) {
    AttachedBody body{a.object.id, a.link, a.touch_links, {}};
    if (!a.object.shapes.empty()) {
      for (std::size_t k = 0; k < a.object.shapes.size(); ++k) {
        const std::string name = a.object.shapes.size() == 1 ? a.object.id : a.object.id + "#" + std::to_string(k);
        body.shapes.push_back(make_collision_object(name, a.object.shapes[k].shape, a.object.pose * a.object.shapes[k].pose));
        body.shapes.back().frame = a.object.pose;
      }
    } else {
      const Transform link_world = link_in_world(checker()->model().link_index(a.link));
      for (const std::uint32_t slot : env.objects().shapes_of(a.object.id)) {
        body.shapes.push_back(env.objects()[slot]);
        body.shapes.back().pose = relative_transform(link_world, body.shapes.back().pose);
        body.shapes.back().frame = relative_transform(link_world, body.shapes.back().frame);
      }
      if (body.shapes.empty()) throw RequestError(path + ": attached object '" + a.object.id + "' has no shapes and the world has no object of that id");
    }
    env.remove_object_shapes(a.object.id);
    try {
      env.attach(std::move(body));
    } catch (const std::invalid_argument& e) {
      throw RequestError(path + ": " + e.what());
    }
  }
}

bool CollisionCheckerNode::set_allowed_collisions(SetAllowedCollisions::Request& req, SetAllowedCollisions::Response& res) {
  return serve("set_allowed_collisions", res, [&] {
    if (req.names_a.size() != req.names_b.size()) {
      throw RequestError(std::to_string(req.names_a.size()) + " names_a but " + std::to_string(req.names_b.size()) + " names_b");
    }
    const RobotModel& model = checker()->model();
    const auto is_link = [&](const std::string& name) { return model.link_index(name) >= 0; };
    std::vector<std::string> names(req.default_names);
    for (std::size_t i = 0; i < req.names_a.size(); ++i) {
      if (is_link(req.names_a[i]) && is_link(req.names_b[i])) {
        throw RequestError("pair " + std::to_string(i) + " (" + req.names_a[i] + ", " + req.names_b[i] +
                           ") names two links: the robot's own pairs come from its SRDF");
      }
      names.push_back(req.names_a[i]);
      names.push_back(req.names_b[i]);
    }
    for (const std::string& name : names) {
      if (const std::string problem = object_id_problem(name); !problem.empty()) throw RequestError("name: " + problem);
    }
    std::vector<std::string> unknown;
    store_->modify([&](Environment& env) {
      NamedAllowedCollisions acm = env.allowed_collisions();
      for (std::size_t i = 0; i < req.names_a.size(); ++i) {
        if (req.remove) acm.remove_entry(req.names_a[i], req.names_b[i]);
        else acm.set_entry(req.names_a[i], req.names_b[i], req.allowed);
      }
      for (const std::string& name : req.default_names) {
        if (req.remove) acm.remove_default(name);
        else acm.set_default(name, req.allowed);
      }
      env.set_allowed_collisions(std::move(acm));
      for (const std::string& name : names) {
        const bool object = env.objects().has_object(name);
        if (!object && !is_link(name) && env.find_attached(name) == nullptr && std::find(unknown.begin(), unknown.end(), name) == unknown.end()) unknown.push_back(name);
      }
    });
    if (!unknown.empty()) {
      res.warning = "neither a link nor a collision object now (kept for one set later):";
      for (const std::string& name : unknown) res.warning += " '" + name + "'";
    }
  });
}

bool CollisionCheckerNode::save_scene(SaveScene::Request& req, SaveScene::Response& res) {
  return serve("save_scene", res, [&] {
    if (req.path.empty()) throw RequestError("path is empty");
    const SceneFile scene = scene_of(*store_->snapshot(), req.name);
    try {
      write_scene_file(scene, req.path);
    } catch (const SceneFileError& e) {
      throw RequestError(e.what());
    }
    const std::string ext = std::filesystem::path(req.path).extension().string();
    if (!scene.attached.empty() && ext != ".yaml" && ext != ".yml") {
      res.warning = std::to_string(scene.attached.size()) + " attached objects not written: a .scene file has no place for them (save as .yaml)";
    }
  });
}

// A new attached object's shapes, built in the link's frame (`link_world`: the link in world_frame now).
std::vector<CollisionObject> CollisionCheckerNode::attached_shapes(const AttachObject::Request& req, const Transform& link_world) const {
  SetCollisionObject::Request geometry;
  geometry.id = req.id;
  geometry.primitives = req.primitives;
  geometry.primitive_poses = req.primitive_poses;
  geometry.meshes = req.meshes;
  geometry.mesh_poses = req.mesh_poses;
  geometry.mesh_resources = req.mesh_resources;
  geometry.mesh_resource_scales = req.mesh_resource_scales;
  geometry.mesh_resource_poses = req.mesh_resource_poses;
  const std::vector<PlacedShape> shapes = object_shapes(geometry, resolver_);
  double triangles = 0.0;
  for (const PlacedShape& s : shapes) triangles += static_cast<double>(s.shape.triangle_count());
  check_limit("attached object '" + req.id + "' with its triangles", triangles, params_.limits.object_triangles,
              "max_object_triangles");
  const bool in_link = req.frame_id.empty() || req.frame_id == req.link;
  const Transform pose = in_link ? to_transform(req.pose) : relative_transform(link_world, frame_to_world(req.frame_id) * to_transform(req.pose));
  std::vector<CollisionObject> out;
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const std::string name = shapes.size() == 1 ? req.id : req.id + "#" + std::to_string(k);
    out.push_back(make_collision_object(name, shapes[k].shape, pose * shapes[k].pose));
    out.back().frame = pose;
  }
  return out;
}

bool CollisionCheckerNode::attach_object(AttachObject::Request& req, AttachObject::Response& res) {
  return serve("attach_object", res, [&] {
    if (const std::string problem = object_id_problem(req.id); !problem.empty()) throw RequestError("attached object " + problem);
    if (req.id == "octree") throw RequestError("attached object id 'octree' is reserved: it names the obstacle octree in contacts");
    const RobotModel& model = checker()->model();  // (the node's checker lives as long as the node)
    const int link = model.link_index(req.link);
    if (link < 0) throw RequestError("no link '" + req.link + "' to attach '" + req.id + "' to");
    if (model.link_index(req.id) >= 0) throw RequestError("attached object id '" + req.id + "' is a link's name");
    for (const std::string& t : req.touch_links) {
      if (model.link_index(t) < 0) throw RequestError("touch link '" + t + "' is not a link");
    }
    const Transform link_world = link_in_world(link);
    const bool given = !req.primitives.empty() || !req.meshes.empty() || !req.mesh_resources.empty();
    AttachedBody body{req.id, req.link, req.touch_links, given ? attached_shapes(req, link_world) : std::vector<CollisionObject>{}};
    const std::shared_ptr<const CollisionChecker> base = checker();
    store_->modify([&](Environment& env) {
      if (!given) {
        for (const std::uint32_t slot : env.objects().shapes_of(req.id)) {
          body.shapes.push_back(env.objects()[slot]);
          body.shapes.back().pose = relative_transform(link_world, body.shapes.back().pose);
          body.shapes.back().frame = relative_transform(link_world, body.shapes.back().frame);
        }
        if (body.shapes.empty()) {
          throw RequestError("no collision object '" + req.id + "' in the world to attach (give its geometry to attach a new one)");
        }
      }
      remove_object_shapes(env, req.id);
      env.attach(std::move(body));
      // Built here, so that a robot that cannot carry it (a limit) changes nothing (without its
      // proxy levels: checker_for builds those after).
      try {
        base->carrying(env, false);
      } catch (const std::invalid_argument& e) {
        throw RequestError(e.what());
      }
    });
    checker_for(store_->snapshot());  // carried at once, its proxy levels started
  });
}

bool CollisionCheckerNode::detach_object(DetachObject::Request& req, DetachObject::Response& res) {
  return serve("detach_object", res, [&] {
    if (const std::string problem = object_id_problem(req.id); !problem.empty()) throw RequestError("attached object " + problem);
    const AttachedBody* now = store_->snapshot()->find_attached(req.id);
    if (now == nullptr) throw RequestError("no attached object '" + req.id + "'");
    const Transform link_world = req.remove ? Transform::Identity() : link_in_world(checker()->model().link_index(now->link));
    store_->modify([&](Environment& env) {
      const AttachedBody* body = env.find_attached(req.id);
      if (body == nullptr) throw RequestError("no attached object '" + req.id + "'");
      if (body->link != now->link) throw RequestError("object '" + req.id + "' was attached again meanwhile: detach it again");
      std::vector<CollisionObject> shapes = body->shapes;
      env.detach(req.id);
      if (req.remove) return;
      for (CollisionObject& o : shapes) {
        o.pose = link_world * o.pose;
        o.frame = link_world * o.frame;
        env.add_object(std::move(o));
      }
    });
  });
}

}  // namespace bvh_collision
