// Which links bound solids and which mesh elements do not, and why (docs/design.md: a
// closed mesh is a solid, so a link inside it collides). A user whose "solid" link lets a
// gripper pass inside it needs to know that its mesh has a hole, and where.
#pragma once

#include <string>
#include <vector>

#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/robot/robot_model.h"

namespace bvh_collision {

struct OpenMesh {
  int link = -1;
  std::size_t element = 0;  // index into the link's collision elements
  std::vector<MeshEdge> edges;
};

struct LinkSolidity {
  std::vector<int> solid_links;        // every element a primitive or a closed mesh
  std::vector<OpenMesh> open_meshes;   // mesh elements that bound no solid
};

LinkSolidity link_solidity(const RobotModel& model);

// One line: "link 'l', collision element 2 (mesh 'package://...'): 4 open edges (3 boundary,
// 1 repeated), e.g. boundary (0.1 0 0)-(0.1 0.2 0)".
std::string describe(const OpenMesh& open, const RobotModel& model);

}  // namespace bvh_collision
