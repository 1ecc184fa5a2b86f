#include "bvh_collision/robot/link_solidity.h"

#include <map>
#include <sstream>

namespace bvh_collision {

LinkSolidity link_solidity(const RobotModel& model) {
  LinkSolidity out;
  for (std::size_t l = 0; l < model.links().size(); ++l) {
    const auto& elements = model.links()[l].collision;
    bool solid = !elements.empty();
    for (std::size_t e = 0; e < elements.size(); ++e) {
      if (!elements[e].mesh) continue;  // spheres and cylinders: solids by definition
      std::vector<MeshEdge> edges = open_edges(*elements[e].mesh);
      if (edges.empty() && !elements[e].mesh->empty()) continue;
      solid = false;
      out.open_meshes.push_back({static_cast<int>(l), e, std::move(edges)});
    }
    if (solid) out.solid_links.push_back(static_cast<int>(l));
  }
  return out;
}

std::string describe(const OpenMesh& open, const RobotModel& model) {
  const CollisionElement& e = model.links()[open.link].collision[open.element];
  std::ostringstream s;
  s << "link '" << model.links()[open.link].name << "', collision element " << open.element + 1 << " (" << e.source
    << "): ";
  if (open.edges.empty()) return s.str() + "no triangles";
  std::map<MeshEdge::Fault, std::size_t> by_fault;
  for (const MeshEdge& edge : open.edges) ++by_fault[edge.fault];
  s << open.edges.size() << " open edge" << (open.edges.size() == 1 ? "" : "s") << " (";
  const char* sep = "";
  for (const auto& [fault, count] : by_fault) {
    s << sep << count << " " << edge_fault_name(fault);
    sep = ", ";
  }
  const MeshEdge& first = open.edges.front();
  s << "), e.g. " << edge_fault_name(first.fault) << " (" << first.from.transpose() << ")-(" << first.to.transpose()
    << ")";
  return s.str();
}

}  // namespace bvh_collision
