#include "bvh_collision/geometry/mesh.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace bvh_collision {
namespace {

// A strict weak order on coordinates that also places NaN (after every number), so that sorting
// a mesh that was never validated stays well defined.
bool coordinate_less(double a, double b) { return a < b || (!std::isnan(a) && std::isnan(b)); }

// Vertex ids after merging equal positions (STL files repeat every vertex per triangle): each
// vertex maps to the first vertex at its position. Sorted, not a tree: a 400k-triangle mesh
// welded in a map took most of a second.
std::vector<std::int32_t> welded_ids(const TriangleMesh& mesh) {
  const auto& v = mesh.vertices;
  std::vector<std::int32_t> order(v.size());
  std::iota(order.begin(), order.end(), 0);
  const auto position_less = [&](std::int32_t i, std::int32_t j) {
    for (int c = 0; c < 3; ++c) {
      if (coordinate_less(v[i][c], v[j][c])) return true;
      if (coordinate_less(v[j][c], v[i][c])) return false;
    }
    return false;
  };
  // Equal positions: the first vertex leads its group (so ids match a first-come weld).
  std::sort(order.begin(), order.end(), [&](std::int32_t i, std::int32_t j) {
    return position_less(i, j) || (!position_less(j, i) && i < j);
  });
  std::vector<std::int32_t> id(v.size());
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool same = k > 0 && !position_less(order[k - 1], order[k]);
    id[order[k]] = same ? id[order[k - 1]] : order[k];
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
  // Closed and oriented iff each directed edge appears once and its reverse appears once too.
  // The directed edges sorted (with their place in the triangle list) find both in O(n log n).
  struct Directed {
    std::int32_t a, b;
    std::size_t at;  // 3 * triangle + corner
    bool operator<(const Directed& o) const { return std::tie(a, b, at) < std::tie(o.a, o.b, o.at); }
  };
  std::vector<Directed> edges;
  edges.reserve(3 * mesh.triangles.size());
  std::vector<char> fault(3 * mesh.triangles.size(), 0);  // 'd' degenerate, 'r' repeated, at the place
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const std::int32_t a = id[mesh.triangles[t][k]], b = id[mesh.triangles[t][(k + 1) % 3]];
      if (a == b) fault[3 * t + k] = 'd';
      else edges.push_back({a, b, 3 * t + k});
    }
  }
  std::sort(edges.begin(), edges.end());
  const auto same = [](const Directed& x, const Directed& y) { return x.a == y.a && x.b == y.b; };
  for (std::size_t i = 1; i < edges.size(); ++i) {
    if (same(edges[i - 1], edges[i]) && (i < 2 || !same(edges[i - 2], edges[i]))) fault[edges[i].at] = 'r';
  }
  std::vector<MeshEdge> out;  // degenerate and repeated edges in triangle order, as met
  for (std::size_t at = 0; at < fault.size(); ++at) {
    if (fault[at] == 0) continue;
    const std::int32_t a = id[mesh.triangles[at / 3][at % 3]], b = id[mesh.triangles[at / 3][(at % 3 + 1) % 3]];
    out.push_back({mesh.vertices[a], mesh.vertices[b], fault[at] == 'd' ? MeshEdge::Fault::kDegenerate : MeshEdge::Fault::kRepeated});
  }
  for (std::size_t i = 0; i < edges.size(); ++i) {  // then boundaries, in edge order
    if (i > 0 && same(edges[i - 1], edges[i])) continue;
    const Directed reverse{edges[i].b, edges[i].a, 0};
    const auto found = std::lower_bound(edges.begin(), edges.end(), reverse);
    if (found == edges.end() || !same(*found, reverse)) {
      out.push_back({mesh.vertices[edges[i].a], mesh.vertices[edges[i].b], MeshEdge::Fault::kBoundary});
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
