// The loader's fuzz targets (docs/design.md "Bad input"): a robot description (URDF text, meshes from
// a fixed package), one mesh file, an SRDF. Each returns what went wrong, or an empty string when
// the input was either refused by name or loaded into something valid. libFuzzer's entry points
// (fuzz_target.cpp) abort on a non-empty answer; test_fuzz_replay runs every corpus file
// through the same functions, so `make test` replays what `make fuzz` found.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace bvh_collision::fuzz {

// URDF text. Loaded: every <collision> of every <link> became a shape of that link, every size,
// vertex and pose finite, a self check at the lower, middle and upper limits gives a finite
// answer, no mesh file name referenced a control character (a NUL cut the name short), and
// bvh_collision_check answers the text (a robot without collision geometry: an error naming it).
// Refused: a RobotDescriptionError or RobotLoadError with a message, the CLI's message too.
// Meshes resolve in `package://fuzz_meshes/meshes/...` (the files of test/fuzz/meshes).
std::string check_robot_description(const std::uint8_t* data, std::size_t size);

// One mesh file: the first byte picks the extension ('s' .stl, 'o' .obj, 'd' .dae; any other
// byte by its value mod 3), the rest is the file. Loaded: at least one triangle, indices in
// range, finite vertices, a triangle of non-zero area, and a hierarchy whose root bounds every
// vertex a triangle uses (an unused vertex is no part of the surface: the first `make fuzz` of
// issue 19 found one outside the root's box once boxes were fitted to the triangles' vertices).
// Refused: a MeshLoadError naming the file.
std::string check_mesh(const std::uint8_t* data, std::size_t size);

// SRDF text, parsed and applied to a five-link robot (revolute, fixed, prismatic and planar
// joints). Loaded: every group state value finite, each joint's values (the robot's, or a
// virtual joint's of the SRDF) the count its type needs, a floating one's quaternion of unit
// length, the matrix symmetric.
// Refused: std::invalid_argument with a message.
std::string check_srdf(const std::uint8_t* data, std::size_t size);

// An OctoMap file: the first byte picks the format (even .bt, odd .ot), the rest is the file.
// Loaded: a positive resolution, every leaf finite and at a depth of the tree, and the tree
// written as a node stream reads back leaf for leaf. Refused: std::runtime_error or
// std::invalid_argument with a message.
std::string check_octree_file(const std::uint8_t* data, std::size_t size);

// A scene file: the first byte picks the form (even: MoveIt .scene text, odd: PlanningScene
// YAML), the rest is the file. Loaded: every object has an id without '#' and at least one
// shape, every dimension positive and finite, every pose finite and rigid, the environment takes
// every shape, and the scene written in its form reads back with the same ids, shapes and
// numbers (to 1e-12). Refused: a SceneFileError with a message.
std::string check_scene_file(const std::uint8_t* data, std::size_t size);

}  // namespace bvh_collision::fuzz
