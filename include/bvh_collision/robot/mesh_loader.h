// Loading collision meshes from files (STL binary/ASCII, Collada, OBJ) through assimp.
#pragma once

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "bvh_collision/geometry/mesh.h"

namespace bvh_collision {

class MeshLoadError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The largest mesh file read (bytes): a robot's collision meshes are far smaller.
constexpr std::uintmax_t kMaxMeshFileBytes = std::uintmax_t(256) << 20;

// Bounds on one mesh import. assimp can crash (a Collada accessor stride of 10^6), allocate
// without end (a non-integer in a Collada <p> list) or take very long on hostile files, so the
// import runs in a child process that is killed past these.
struct MeshImportLimits {
  std::size_t memory_bytes = std::size_t(1) << 30;  // resident memory the importer may add
  double seconds = 120.0;
  // false: import in this process, with no bound and no cache. For the loader's fuzz target and
  // its replay, where the sanitizers and the fuzzer's coverage must see the import itself.
  bool isolated = true;
};

// Reads every triangle of every mesh in the file, with node transforms applied (for Collada the
// scene root's own transform is reset to identity, the ROS convention, child transforms kept),
// scaled per axis. A negative scale with an odd number of negative factors mirrors the mesh;
// triangle winding is then reversed so that outward faces stay outward. Identical vertices are
// merged. Throws MeshLoadError naming the file on any failure: not a regular file, larger than
// kMaxMeshFileBytes, unreadable, no triangle, a face naming a vertex that does not exist, or a
// vertex a triangle uses that is not finite, or an importer that crashed or ran past `limits`.
TriangleMesh load_mesh(const std::string& path, const Vec3& scale = Vec3::Ones(), const MeshImportLimits& limits = {});

}  // namespace bvh_collision
