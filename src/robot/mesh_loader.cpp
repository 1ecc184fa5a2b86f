#include "bvh_collision/robot/mesh_loader.h"

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace bvh_collision {
namespace {

Mat3 rotation_part(const aiMatrix4x4& m, Vec3& translation) {
  Mat3 r;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j];
    translation[i] = m[i][3];
  }
  return r;
}

void append_node(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent, bool is_root,
                 const Vec3& scale, TriangleMesh& out) {
  // ROS convention for Collada: the root node's transform (up-axis conversion) is ignored.
  const aiMatrix4x4 transform = is_root ? parent : parent * node->mTransformation;
  Vec3 t;
  const Mat3 r = rotation_part(transform, t);
  for (unsigned m = 0; m < node->mNumMeshes; ++m) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[m]];
    const auto base = static_cast<std::int32_t>(out.vertices.size());
    for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
      const aiVector3D& p = mesh->mVertices[v];
      out.vertices.push_back((r * Vec3(p.x, p.y, p.z) + t).cwiseProduct(scale));
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines are not collision geometry
      out.triangles.push_back({base + static_cast<std::int32_t>(face.mIndices[0]),
                               base + static_cast<std::int32_t>(face.mIndices[1]),
                               base + static_cast<std::int32_t>(face.mIndices[2])});
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) {
    append_node(scene, node->mChildren[c], transform, false, scale, out);
  }
}

}  // namespace

TriangleMesh load_mesh(const std::string& path, const Vec3& scale) {
  if (!std::filesystem::is_regular_file(path)) {
    throw MeshLoadError("mesh file '" + path + "' does not exist or is not a file");
  }
  if (!scale.allFinite() || (scale.array() == 0.0).any()) {
    throw MeshLoadError("mesh file '" + path + "': scale must be finite and non-zero");
  }
  Assimp::Importer importer;
  // Keep every triangle: no degenerate or invalid-data removal (a zero-area triangle still collides).
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      path, aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  if (scene == nullptr || scene->mRootNode == nullptr || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
    throw MeshLoadError("mesh file '" + path + "' cannot be read: " + importer.GetErrorString());
  }
  TriangleMesh mesh;
  append_node(scene, scene->mRootNode, aiMatrix4x4(), true, scale, mesh);
  if (scale.x() * scale.y() * scale.z() < 0.0) {
    for (auto& t : mesh.triangles) std::swap(t[1], t[2]);  // mirrored: keep outward winding
  }
  return mesh;
}

}  // namespace bvh_collision
