// Planning scenes as MoveIt users keep them: the `.scene` text that MoveIt's "export scene" writes
// (PlanningScene::saveGeometryToStream, both its formats) read and written. A scene is world
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
  Transform pose;  // in the scene's (world) frame
  std::vector<SceneShape> shapes;
};

struct SceneFile {
  std::string name;
  std::vector<SceneObject> objects;  // ids unique: a later object of the same id replaced an earlier one

  std::size_t shape_count() const;
  // Every shape as the checker's collision object, posed in the world (`id#k` as above).
  std::vector<CollisionObject> collision_objects() const;
  // An environment of those objects and an empty octree of `octree_resolution`.
  Environment environment(double octree_resolution = 0.05) const;
};

class SceneFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// `source` names the input in errors (a path). Planes (infinite) and unknown shape types are
// refused by name; colours and subframes are read and dropped.
SceneFile read_scene_text(std::istream& in, const std::string& source);
// A regular file of at most 64 MiB, read as above.
SceneFile read_scene_file(const std::string& path);
// MoveIt's newer format (object poses and subframe counts), every number to 17 digits so that
// reading it back gives the same doubles.
void write_scene_text(const SceneFile& scene, std::ostream& out);

}  // namespace bvh_collision
