// A scene placed in the world and applied to an environment as MoveIt applies a PlanningScene
// (io/scene_file.h).
#include <algorithm>
#include <set>
#include <unordered_map>
#include <unordered_set>

#include "bvh_collision/io/scene_file.h"

namespace bvh_collision {

namespace {

std::string where(const SceneObject& o) {
  return "object '" + o.id + "'" + (o.line > 0 ? " (line " + std::to_string(o.line) + ")" : "");
}

// The frames a scene's own objects name, by what they were placed at so far.
class SceneFrames {
 public:
  SceneFrames(const SceneFile& scene, const SceneFrameLookup& lookup) : scene_(scene), lookup_(lookup) {}

  std::optional<Transform> find(std::string frame) const {
    if (!frame.empty() && frame[0] == '/') frame.erase(0, 1);
    if (frame.empty()) return Transform::Identity();
    if (lookup_) {
      if (std::optional<Transform> t = lookup_(frame)) return t;
    }
    if (const auto it = objects_.find(frame); it != objects_.end()) return it->second;
    if (const auto it = subframes_.find(frame); it != subframes_.end()) return it->second;
    for (const SceneFixedFrame& f : scene_.fixed_frames) {
      if (f.frame != frame || f.parent == frame) continue;
      if (std::optional<Transform> parent = find(f.parent)) return *parent * f.pose;
    }
    return std::nullopt;
  }
  // Object `o`, now in the world at `pose`, as a frame for the objects after it.
  void add(const SceneObject& o, const Transform& pose) {
    objects_.emplace(o.id, pose);
    for (const auto& [name, sub] : o.subframes) subframes_.emplace(o.id + "/" + name, pose * sub);
  }

 private:
  const SceneFile& scene_;
  const SceneFrameLookup& lookup_;
  std::unordered_map<std::string, Transform> objects_, subframes_;
};

// The shapes object `id` has in `env`, in their order (id, or id#0, id#1, ...).
std::vector<CollisionObject> shapes_now(const Environment& env, const std::string& id) {
  std::vector<std::pair<std::size_t, const CollisionObject*>> parts;
  for (const std::uint32_t slot : env.objects().shapes_of(id)) {
    const CollisionObject& o = env.objects()[slot];
    parts.emplace_back(o.id == id ? 0 : std::stoul(o.id.substr(id.size() + 1)), &o);
  }
  std::sort(parts.begin(), parts.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<CollisionObject> out;
  for (const auto& [k, o] : parts) out.push_back(*o);
  return out;
}

// Object `id` made of these shapes (named id, or id#k for several), replacing what it had.
void set_shapes(Environment& env, const std::string& id, std::vector<CollisionObject> shapes) {
  env.remove_object_shapes(id);
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    shapes[k].id = shapes.size() == 1 ? id : id + "#" + std::to_string(k);
    env.add_object(std::move(shapes[k]));
  }
}

// The entry's shapes built, each at frame * its pose, the object's frame `object_frame`.
std::vector<CollisionObject> built(const SceneObject& o, const Transform& frame, const Transform& object_frame) {
  std::vector<CollisionObject> out;
  for (const SceneShape& s : o.shapes) {
    try {
      out.push_back(make_collision_object(o.id, s.shape, frame * s.pose));
    } catch (const std::invalid_argument& e) {
      throw SceneFileError(where(o) + ": " + e.what());
    }
    out.back().frame = object_frame;
  }
  return out;
}

void move_object(const SceneObject& o, Environment& env) {
  std::vector<CollisionObject> shapes = shapes_now(env, o.id);
  if (shapes.empty()) throw SceneFileError(where(o) + ": MOVE of an object the world does not hold");
  if (!o.shapes.empty() && o.shapes.size() != shapes.size()) {
    throw SceneFileError(where(o) + ": MOVE gives " + std::to_string(o.shapes.size()) + " shape poses for an object of " +
                         std::to_string(shapes.size()) + " shapes");
  }
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    const Transform within = o.shapes.empty() ? relative_transform(shapes[k].frame, shapes[k].pose) : o.shapes[k].pose;
    shapes[k].pose = o.pose * within;
    shapes[k].frame = o.pose;
  }
  set_shapes(env, o.id, std::move(shapes));
}

}  // namespace

void place_in_world(SceneFile& scene, const SceneFrameLookup& lookup) {
  SceneFrames frames(scene, lookup);
  for (SceneObject& o : scene.objects) {
    const std::optional<Transform> frame = frames.find(o.frame_id);
    if (!frame) throw SceneFileError(where(o) + ": frame '" + o.frame_id + "' is not known (neither the world's nor the scene's)");
    o.pose = *frame * o.pose;
    o.frame_id.clear();
    if (o.operation == SceneOperation::kAdd || o.operation == SceneOperation::kAppend) frames.add(o, o.pose);
  }
  for (SceneAttachedObject& a : scene.attached) {
    SceneObject& o = a.object;
    if (o.frame_id.empty() || o.frame_id == a.link || o.frame_id == "/" + a.link) {
      o.frame_id.clear();
      continue;
    }
    const std::optional<Transform> frame = frames.find(o.frame_id);
    const std::optional<Transform> link = lookup ? lookup(a.link) : std::nullopt;
    if (!frame) throw SceneFileError("attached " + where(o) + ": frame '" + o.frame_id + "' is not known");
    if (!link) throw SceneFileError("attached " + where(o) + ": link '" + a.link + "' is not known");
    o.pose = relative_transform(*link, *frame * o.pose);
    o.frame_id.clear();
  }
}

void apply_scene_objects(const SceneFile& scene, Environment& env, std::vector<std::string>& warnings) {
  // Ids this scene has set: a later ADD of one of them adds to it (never drops a listed shape).
  std::unordered_set<std::string> set_here;
  for (const SceneObject& o : scene.objects) {
    const bool again = set_here.count(o.id) > 0;
    switch (o.operation) {
      case SceneOperation::kAdd: {
        std::vector<CollisionObject> shapes = again ? shapes_now(env, o.id) : std::vector<CollisionObject>{};
        const Transform frame = shapes.empty() ? o.pose : shapes.front().frame;
        for (CollisionObject& s : built(o, o.pose, frame)) shapes.push_back(std::move(s));
        set_shapes(env, o.id, std::move(shapes));
        set_here.insert(o.id);
        break;
      }
      case SceneOperation::kAppend: {  // in the existing object's frame, as MoveIt's World does
        std::vector<CollisionObject> shapes = shapes_now(env, o.id);
        const Transform frame = shapes.empty() ? o.pose : shapes.front().frame;
        for (CollisionObject& s : built(o, frame, frame)) shapes.push_back(std::move(s));
        set_shapes(env, o.id, std::move(shapes));
        set_here.insert(o.id);
        break;
      }
      case SceneOperation::kRemove:
        if (o.id.empty()) {
          env.clear_objects();
          set_here.clear();
        } else if (env.remove_object_shapes(o.id) == 0) {
          warnings.push_back(where(o) + ": REMOVE of an object the world does not hold (nothing removed)");
        }
        set_here.erase(o.id);
        break;
      case SceneOperation::kMove:
        move_object(o, env);
        break;
    }
  }
}

std::size_t SceneFile::shape_count() const {
  std::size_t n = 0;
  for (const SceneObject& o : objects) n += o.shapes.size();
  for (const SceneAttachedObject& a : attached) n += a.object.shapes.size();
  return n;
}

std::vector<CollisionObject> SceneFile::collision_objects() const {
  const Environment env = environment();
  return std::vector<CollisionObject>(env.objects().begin(), env.objects().end());
}

Environment SceneFile::environment(double octree_resolution) const {
  Environment env(octree_resolution);
  std::vector<std::string> ignored;
  apply_scene_objects(*this, env, ignored);
  for (const SceneAttachedObject& a : attached) {
    AttachedBody body{a.object.id, a.link, a.touch_links, built(a.object, a.object.pose, a.object.pose)};
    if (body.shapes.size() > 1) {
      for (std::size_t k = 0; k < body.shapes.size(); ++k) body.shapes[k].id = a.object.id + "#" + std::to_string(k);
    }
    if (body.shapes.empty()) throw SceneFileError("attached " + where(a.object) + ": no geometry");
    env.remove_object_shapes(a.object.id);  // attached, it is not in the world too
    try {
      env.attach(std::move(body));
    } catch (const std::invalid_argument& e) {
      throw SceneFileError("attached " + where(a.object) + ": " + e.what());
    }
  }
  // Every entry: the checks against objects read only those that name one (a pair of links is
  // the robot's matrix, which this does not change).
  NamedAllowedCollisions acm;
  for (const AllowedCollision& e : allowed_collisions) acm.set_entry(e.a, e.b, e.allowed);
  for (const auto& [name, allowed] : default_allowed) acm.set_default(name, allowed);
  env.set_allowed_collisions(std::move(acm));
  return env;
}

}  // namespace bvh_collision
