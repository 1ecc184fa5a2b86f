// Loading collision meshes from files (STL binary/ASCII, Collada, OBJ) through assimp.
#pragma once

#include <stdexcept>
#include <string>

#include "bvh_collision/geometry/mesh.h"

namespace bvh_collision {

class MeshLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reads every triangle of every mesh in the file, with node transforms applied (for Collada the
// scene root's own transform is reset to identity, the ROS convention, child transforms kept),
// scaled per axis. A negative scale with an odd number of negative factors mirrors the mesh;
// triangle winding is then reversed so that outward faces stay outward. Identical vertices are
// merged. Throws MeshLoadError naming the file on any failure.
TriangleMesh load_mesh(const std::string& path, const Vec3& scale = Vec3::Ones());

}  // namespace bvh_collision
