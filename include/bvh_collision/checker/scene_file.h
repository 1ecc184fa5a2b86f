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

#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "bvh_collision/checker/environment.h"

namespace bvh_collision {

struct SceneShape {
  ObjectShape shape;
  Transform pose;  // in the object's frame
};

struct SceneObject {
  std::string id;
  Transform pose;  // in the frame `frame_id` names (empty: the scene's world frame)
  std::vector<SceneShape> shapes;
  std::string frame_id;  // YAML's header.frame_id; .scene objects are in the world frame
};

// An allowed-collision entry of a YAML scene: whether `a` and `b` may touch (MoveIt's matrix,
// one entry per pair; a name may be a link or an object id).
struct AllowedCollision {
  std::string a, b;
  bool allowed = false;
};

struct SceneFile {
  std::string name;
  std::vector<SceneObject> objects;  // ids unique: a later object of the same id replaced an earlier one
  // YAML only: robot_state.joint_state's values, and the allowed-collision matrix as its pairs.
  std::vector<std::pair<std::string, double>> joint_values;
  std::vector<AllowedCollision> allowed_collisions;

  std::size_t shape_count() const;
  // Every shape as the checker's collision object (`id#k` as above), posed in the world taking
  // every frame_id as the world frame (the node places a named frame through tf2 first).
  std::vector<CollisionObject> collision_objects() const;
  // An environment of those objects, with the allowed-collision entries (those naming an object
  // are the ones its checks read), and an empty octree of `octree_resolution`.
  Environment environment(double octree_resolution = 0.05) const;
};

class SceneFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `source` names the input in errors (a path). Planes (infinite) and unknown shape types are
// refused by name; colours and subframes are read and dropped.
SceneFile read_scene_text(std::istream& in, const std::string& source);
// A moveit_msgs/PlanningScene in YAML (what `rostopic echo` prints, or MoveIt's benchmark scenes):
// name; world.collision_objects (id, header.frame_id, pose, primitives BOX, SPHERE, CYLINDER and
// CONE with their primitive_poses, meshes with their mesh_poses; operation ADD); robot_state's
// joint_state names and positions; allowed_collision_matrix's entry_names and entry_values.
// Refused by name (with the line): planes, other primitive types or operations, attached
// objects, multi-DOF joint states, an octomap with data (use octree_file), and any malformed
// field. Fields the checker has no use for (colours, padding, fixed frames) are left alone.
SceneFile read_scene_yaml(std::istream& in, const std::string& source);
// The scene as such YAML (what read_scene_yaml reads back to the same doubles): an object's
// primitives are written before its meshes, as the message holds them.
void write_scene_yaml(const SceneFile& scene, std::ostream& out);
// A regular file of at most 64 MiB: YAML when its name ends in .yaml or .yml, else .scene text.
SceneFile read_scene_file(const std::string& path);
// MoveIt's newer format (object poses and subframe counts), every number to 17 digits so that
// reading it back gives the same doubles.
void write_scene_text(const SceneFile& scene, std::ostream& out);
// By the path's extension, as read_scene_file reads it; throws SceneFileError when it cannot write.
void write_scene_file(const SceneFile& scene, const std::string& path);

}  // namespace bvh_collision
