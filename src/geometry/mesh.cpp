#include "bvh_collision/geometry/mesh.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>

namespace bvh_collision {
namespace {

// Vertex ids after merging equal positions (STL files repeat every vertex per triangle).
std::vector<std::int32_t> welded_ids(const TriangleMesh& mesh) {
  std::map<std::tuple<double, double, double>, std::int32_t> first;
  std::vector<std::int32_t> id(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Vec3& v = mesh.vertices[i];
    id[i] = first.emplace(std::make_tuple(v.x(), v.y(), v.z()), static_cast<std::int32_t>(i)).first->second;
  }
  return id;
}

std::int32_t find_root(std::vector<std::int32_t>& parent, std::int32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];
    x = parent[x];
  }
  return x;
}

}  // namespace

std::vector<MeshEdge> open_edges(const TriangleMesh& mesh) {
  const std::vector<std::int32_t> id = welded_ids(mesh);
  // Directed edge -> count: closed and oriented iff each directed edge appears once and its
  // reverse appears once too.
  std::map<std::pair<std::int32_t, std::int32_t>, int> directed;
  std::vector<MeshEdge> out;
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = id[t[k]], b = id[t[(k + 1) % 3]];
      if (a == b) {
        out.push_back({mesh.vertices[a], mesh.vertices[b], MeshEdge::Fault::kDegenerate});
      } else if (++directed[{a, b}] == 2) {
        out.push_back({mesh.vertices[a], mesh.vertices[b], MeshEdge::Fault::kRepeated});
      }
    }
  }
  for (const auto& [edge, count] : directed) {
    if (directed.find({edge.second, edge.first}) == directed.end()) {
      out.push_back({mesh.vertices[edge.first], mesh.vertices[edge.second], MeshEdge::Fault::kBoundary});
    }
  }
  return out;
}

bool is_closed(const TriangleMesh& mesh) { return !mesh.triangles.empty() && open_edges(mesh).empty(); }

const char* edge_fault_name(MeshEdge::Fault f) {
  switch (f) {
    case MeshEdge::Fault::kBoundary: return "boundary";
    case MeshEdge::Fault::kRepeated: return "repeated";
    case MeshEdge::Fault::kDegenerate: return "degenerate";
  }
  return "?";
}

std::vector<std::int32_t> component_representatives(const TriangleMesh& mesh) {
  const std::vector<std::int32_t> id = welded_ids(mesh);
  std::vector<std::int32_t> parent(mesh.vertices.size());
  std::iota(parent.begin(), parent.end(), 0);
  for (const auto& t : mesh.triangles) {
    const std::int32_t r0 = find_root(parent, id[t[0]]);
    for (int k = 1; k < 3; ++k) parent[find_root(parent, id[t[k]])] = r0;
  }
  std::vector<std::int32_t> reps;
  std::vector<bool> seen(mesh.vertices.size(), false);
  for (const auto& t : mesh.triangles) {
    const std::int32_t root = find_root(parent, id[t[0]]);
    if (!seen[root]) {
      seen[root] = true;
      reps.push_back(t[0]);
    }
  }
  return reps;
}

TriangleMesh box_mesh(const Vec3& size) {
  TriangleMesh m;
  const Vec3 h = 0.5 * size;
  for (int i = 0; i < 8; ++i) {
    m.vertices.emplace_back((i & 4) ? h.x() : -h.x(), (i & 2) ? h.y() : -h.y(), (i & 1) ? h.z() : -h.z());
  }
  // Outward winding (counter-clockwise seen from outside).
  m.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                 {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  return m;
}

std::vector<Vec3> used_vertices(const TriangleMesh& mesh) {
  std::vector<char> used(mesh.vertices.size(), 0);
  for (const auto& t : mesh.triangles) {
    for (const std::int32_t v : t) used[v] = 1;
  }
  std::vector<Vec3> out;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (used[v]) out.push_back(mesh.vertices[v]);
  }
  return out;
}

TriangleMesh cylinder_mesh(double r, double l, double max_error) {
  int sides = 16;
  while (sides < 512 && r * (1.0 / std::cos(M_PI / sides) - 1.0) > max_error) sides *= 2;
  const double R = r / std::cos(M_PI / sides);  // the polygon's edges touch the circle
  TriangleMesh m;
  for (int i = 0; i < sides; ++i) {
    const double a = 2 * M_PI * i / sides;
    m.vertices.emplace_back(R * std::cos(a), R * std::sin(a), -l / 2);
    m.vertices.emplace_back(R * std::cos(a), R * std::sin(a), l / 2);
  }
  const int bottom = static_cast<int>(m.vertices.size()), top = bottom + 1;
  m.vertices.emplace_back(0, 0, -l / 2);
  m.vertices.emplace_back(0, 0, l / 2);
  for (int i = 0; i < sides; ++i) {
    const int b0 = 2 * i, t0 = 2 * i + 1, b1 = 2 * ((i + 1) % sides), t1 = b1 + 1;
    m.triangles.push_back({b0, b1, t1});
    m.triangles.push_back({b0, t1, t0});
    m.triangles.push_back({bottom, b1, b0});
    m.triangles.push_back({top, t0, t1});
  }
  return m;
}


}  // namespace bvh_collision
