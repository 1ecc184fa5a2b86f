// An indexed triangle mesh and the topological facts the collision layers need.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::int32_t, 3>> triangles;

  Triangle triangle(std::size_t i) const {
    const auto& t = triangles[i];
    return Triangle{{vertices[t[0]], vertices[t[1]], vertices[t[2]]}};
  }
  bool empty() const { return triangles.empty(); }
};

// Closed (watertight) and consistently oriented: after merging vertices at equal positions, every
// edge is used by exactly two triangles, once in each direction. Such a mesh bounds a solid.
bool is_closed(const TriangleMesh& mesh);

// An edge that keeps a mesh from being closed, and why: no triangle uses it the other way (a hole
// or a flipped neighbour), a second triangle uses it the same way (inconsistent orientation or
// more than two triangles on it), or its two ends are one point.
struct MeshEdge {
  enum class Fault { kBoundary, kRepeated, kDegenerate };
  Vec3 from = Vec3::Zero(), to = Vec3::Zero();
  Fault fault = Fault::kBoundary;
};
const char* edge_fault_name(MeshEdge::Fault f);

// Every such edge (none for a closed mesh).
std::vector<MeshEdge> open_edges(const TriangleMesh& mesh);

// One vertex (as an index) from each connected component (triangles sharing a vertex position).
// A mesh wholly inside a solid has all of these inside it; one outside has none.
std::vector<std::int32_t> component_representatives(const TriangleMesh& mesh);

// The vertices some triangle uses (each once, in index order): a mesh's vertex list may hold
// points that are not on its surface.
std::vector<Vec3> used_vertices(const TriangleMesh& mesh);

// The 12 triangles of an axis-aligned box centred on the origin, outward winding.
TriangleMesh box_mesh(const Vec3& size);

// A regular prism circumscribing the cylinder (radius r, length l, axis z, centred; closed,
// outward winding), with the fewest sides (16 to 512) that keep every point of the prism within
// max_error of the cylinder: it only ever makes the cylinder larger, never misses a contact.
TriangleMesh cylinder_mesh(double r, double l, double max_error);

}  // namespace bvh_collision
