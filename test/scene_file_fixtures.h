// Helpers of the scene-file tests (test_scene_file.cpp, test_scene_spellings.cpp): a scene read
// from a string in either format, and a small closed mesh to put in one.
#pragma once

#include <sstream>
#include <string>

#include "bvh_collision/io/scene_file.h"

namespace bvh_collision::test {

inline SceneFile read_yaml(const std::string& text) {
  std::istringstream in(text);
  return read_scene_yaml(in, "test.yaml");
}

inline SceneFile read_text(const std::string& text) {
  std::istringstream in(text);
  return read_scene_text(in, "test.scene");
}

// A tetrahedron with edges of length s along the axes, its faces wound outwards.
inline TriangleMesh tetrahedron(double s) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {s, 0, 0}, {0, s, 0}, {0, 0, s}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

}  // namespace bvh_collision::test
