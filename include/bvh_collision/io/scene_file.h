// Planning scenes as MoveIt users keep them: the `.scene` text that MoveIt's "export scene" writes
// (PlanningScene::saveGeometryToStream, both its formats) read and written, and a
// moveit_msgs/PlanningScene as YAML read (its world objects, its robot state's joint values and
// its allowed-collision entries, with the line of each field in errors). A scene is world
// objects, each an id, a pose and one or more shapes posed in the object's frame; the checker
// holds each shape as one collision object, `id#k` for the k-th shape of an object of several
// (as the node's set_collision_object names them), the object's own id for an object of one.
//
// A malformed file is refused with a SceneFileError that names the file, the line and the field
// (`scene.scene:14: object 'table' shape 2 (box): size 3 is not a positive number`); nothing
// is returned from it, so a caller that loads into an environment changes nothing.
#pragma once

#include <functional>
#include <istream>
#include <optional>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvh_collision/world/environment.h"

namespace bvh_collision {

struct SceneShape {
  ObjectShape shape;
  Transform pose;  // in the object's frame
};

// What a PlanningScene's CollisionObject asks of the world (moveit_msgs/CollisionObject's
// operation): ADD sets the object of its id (replacing one of that id), APPEND adds its shapes to
// the object of its id (in that object's frame; creating it when there is none), REMOVE takes the
// object out (every object for an empty id), MOVE moves the object to its pose (and its shapes to
// their poses when it gives them, in the order the object holds them).
enum class SceneOperation { kAdd, kAppend, kRemove, kMove };

struct SceneObject {
  SceneObject() = default;
  // An object of these shapes (the common case: what a scene generator or a test writes).
  SceneObject(std::string id, const Transform& pose, std::vector<SceneShape> shapes, std::string frame_id = {})
      : id(std::move(id)), pose(pose), shapes(std::move(shapes)), frame_id(std::move(frame_id)) {}

  std::string id;
  Transform pose;  // in the frame `frame_id` names (empty: the scene's world frame)
  std::vector<SceneShape> shapes;
  std::string frame_id;  // YAML's header.frame_id; .scene objects are in the world frame
  // Named frames fixed in the object (MoveIt's subframes), posed in the object's frame: kept, and
  // usable as a later object's frame_id ("id/name").
  std::vector<std::pair<std::string, Transform>> subframes;
  SceneOperation operation = SceneOperation::kAdd;
  int line = 0;  // where it starts in its file, for messages (0: not from a file)
};

// An object the robot holds (robot_state.attached_collision_objects): the object, posed in its
// frame_id (empty, or `link` itself: in the link's frame), hung from `link`; `touch_links` may
// touch it besides `link`.
struct SceneAttachedObject {
  std::string link;
  SceneObject object;
  std::vector<std::string> touch_links;
};

// An allowed-collision entry of a YAML scene: whether `a` and `b` may touch (MoveIt's matrix,
// one entry per pair; a name may be a link or an object id).
struct AllowedCollision {
  std::string a, b;
  bool allowed = false;
};

// A fixed frame of the scene (fixed_frame_transforms): `frame` posed in the frame `parent` names.
struct SceneFixedFrame {
  std::string frame, parent;
  Transform pose;
};

// The frames of the world outside the scene: the pose in the world frame of the frame a name
// names (the world frame itself, a robot link), or nothing when it names none.
using SceneFrameLookup = std::function<std::optional<Transform>(const std::string& frame)>;

struct SceneFile {
  std::string name;
  // A diff (PlanningScene's is_diff): its objects are changes applied in order to the world that
  // is there; otherwise the scene is the whole world, its objects of distinct ids, each ADD.
  bool is_diff = false;
  std::vector<SceneObject> objects;
  std::vector<SceneAttachedObject> attached;
  // YAML only: robot_state.joint_state's values, the allowed-collision matrix as its pairs and
  // its default entries (a name's entry for every name the matrix does not pair it with).
  std::vector<std::pair<std::string, double>> joint_values;
  std::vector<AllowedCollision> allowed_collisions;
  std::vector<std::pair<std::string, bool>> default_allowed;
  std::vector<SceneFixedFrame> fixed_frames;
  // What the file holds that is read and not used, each naming the file, the line and the field
  // (MoveIt logs these and loads the scene; so do we).
  std::vector<std::string> warnings;

  std::size_t shape_count() const;
  // Every shape as the checker's collision object (`id#k` as above), posed in the world taking
  // every frame_id as the world frame (place_in_world places named frames first).
  std::vector<CollisionObject> collision_objects() const;
  // An environment of those objects (a diff applied to an empty world), with the attached
  // objects hung from their links and the allowed-collision entries (those naming an object are
  // the ones its checks read), and an empty octree of `octree_resolution`.
  Environment environment(double octree_resolution = 0.05) const;
};

class SceneFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `source` names the input in errors (a path). Planes (infinite) and unknown shape types are
// refused by name; colours are read and dropped, subframes kept. A second object of an id already
// read adds its shapes to that object, each where its own entry places it (MoveIt before 1.1.12
// adds them; 1.1.12 and later replace the object: a shape the file lists is never dropped here),
// with a warning naming the id and both lines.
SceneFile read_scene_text(std::istream& in, const std::string& source);
// A moveit_msgs/PlanningScene in YAML, in either spelling, block or flow style: what `rostopic
// echo` and write_scene_yaml write (primitive types as shape_msgs numbers, points and quaternions
// as maps, matrix rows as {enabled: [...]}), and what MoveIt benchmarking tools write (types by
// name in any case, points as [x, y, z] and quaternions as [x, y, z, w], rows as bare lists,
// operations by name). Read: name, is_diff; world.collision_objects (id, header.frame_id, the
// object's pose with its shapes placed in it as MoveIt 1.1 and later do, primitives BOX, SPHERE,
// CYLINDER and CONE, meshes, subframes, operation); robot_state's joint_state and
// attached_collision_objects; allowed_collision_matrix with its default entries;
// fixed_frame_transforms. Two entries of one id in a scene merge as in read_scene_text; REMOVE
// and MOVE are refused outside a diff. Refused by name (with the line): planes, other primitive
// types or operations, multi-DOF joint states, an octomap with data (use octree_file), a list
// of the wrong length, and any malformed field. Fields the checker has no use for (colours,
// object types, weights) are left alone; link padding and scale, which change answers, are
// warned of (not applied: the node's padding parameters decide).
SceneFile read_scene_yaml(std::istream& in, const std::string& source);
// The scene as such YAML (what read_scene_yaml reads back to the same doubles): an object's
// primitives are written before its meshes, as the message holds them.
void write_scene_yaml(const SceneFile& scene, std::ostream& out);
// A regular file of at most 64 MiB: YAML when its name ends in .yaml or .yml, else .scene text.
SceneFile read_scene_file(const std::string& path);

// The scene with every object and attached object posed in the world frame (frame_id cleared):
// a frame is the world's when `lookup` knows it (a leading '/' ignored), else an object of the
// scene read before (its id; "id/subframe" for one of its subframes), else one of the scene's
// fixed frames. An attached object's frame is its link's when empty. Throws SceneFileError
// naming the object, its line and the frame that none of these knows (MoveIt refuses the object).
void place_in_world(SceneFile& scene, const SceneFrameLookup& lookup);

// The scene's objects applied to `env` as MoveIt applies a PlanningScene message (objects posed
// in the world: place_in_world): each object of a whole scene sets the object of its id; a diff's
// changes in order, ADD replacing, APPEND adding shapes in the existing object's frame, REMOVE and
// MOVE as SceneOperation says. Throws SceneFileError (and `env` may be partly changed: apply it
// to a copy) for a MOVE of an object that is not there, or with a count of shape poses that is
// not the object's. A REMOVE of an object that is not there is a warning, as in MoveIt.
void apply_scene_objects(const SceneFile& scene, Environment& env, std::vector<std::string>& warnings);
// MoveIt's newer format (object poses and subframes), every number to 17 digits so that reading
// it back gives the same doubles. The world's objects only, as MoveIt writes it: attached objects
// have no place in it (YAML keeps them), and a diff has no .scene form (std::invalid_argument).
void write_scene_text(const SceneFile& scene, std::ostream& out);
// By the path's extension, as read_scene_file reads it; throws SceneFileError when it cannot write.
void write_scene_file(const SceneFile& scene, const std::string& path);

}  // namespace bvh_collision
