// Meshes and poses for BVH tests: random meshes, real link meshes from ../shared/robots, and
// poses in near contact.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <fstream>
#include <random>
#include <string>

#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/robot/mesh_loader.h"
#include "robot_data.h"

namespace bvh_collision::test {

inline Transform random_rotation(std::mt19937_64& rng, const Vec3& t = Vec3::Zero()) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return {q.toRotationMatrix(), t};
}

// A closed sphere-like mesh (latitude/longitude) with radial noise: a solid with curvature.
inline TriangleMesh bumpy_sphere(std::mt19937_64& rng, double radius, int rings, int segments, double noise) {
  TriangleMesh m;
  std::uniform_real_distribution<double> u(1.0 - noise, 1.0 + noise);
  m.vertices.push_back(Vec3(0, 0, radius * u(rng)));
  for (int r = 1; r < rings; ++r) {
    const double theta = M_PI * r / rings;
    for (int s = 0; s < segments; ++s) {
      const double phi = 2 * M_PI * s / segments;
      m.vertices.push_back(radius * u(rng) * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)));
    }
  }
  m.vertices.push_back(Vec3(0, 0, -radius * u(rng)));
  const int south = static_cast<int>(m.vertices.size()) - 1;
  auto ring = [&](int r, int s) { return 1 + (r - 1) * segments + (s % segments); };
  for (int s = 0; s < segments; ++s) m.triangles.push_back({0, ring(1, s), ring(1, s + 1)});
  for (int r = 1; r < rings - 1; ++r) {
    for (int s = 0; s < segments; ++s) {
      m.triangles.push_back({ring(r, s), ring(r + 1, s), ring(r + 1, s + 1)});
      m.triangles.push_back({ring(r, s), ring(r + 1, s + 1), ring(r, s + 1)});
    }
  }
  for (int s = 0; s < segments; ++s) m.triangles.push_back({south, ring(rings - 1, s + 1), ring(rings - 1, s)});
  return m;
}

// Random triangles in a box: a soup with slivers, overlaps and no topology.
// A binary STL of the mesh (single precision, zero normals), for tests that load files.
inline void write_binary_stl(const TriangleMesh& mesh, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  const char header[80] = "bvh_collision test mesh";
  out.write(header, 80);
  const auto n = static_cast<std::uint32_t>(mesh.triangles.size());
  out.write(reinterpret_cast<const char*>(&n), 4);
  for (const auto& t : mesh.triangles) {
    float facet[12] = {};
    for (int k = 0; k < 3; ++k) {
      for (int c = 0; c < 3; ++c) facet[3 + 3 * k + c] = static_cast<float>(mesh.vertices[t[k]][c]);
    }
    out.write(reinterpret_cast<const char*>(facet), sizeof(facet));
    const std::uint16_t attributes = 0;
    out.write(reinterpret_cast<const char*>(&attributes), 2);
  }
}

inline TriangleMesh triangle_soup(std::mt19937_64& rng, int n, double size, double triangle_size) {
  TriangleMesh m;
  std::uniform_real_distribution<double> pos(-size / 2, size / 2), off(-triangle_size, triangle_size);
  for (int i = 0; i < n; ++i) {
    const Vec3 c(pos(rng), pos(rng), pos(rng));
    const auto base = static_cast<std::int32_t>(m.vertices.size());
    for (int k = 0; k < 3; ++k) m.vertices.push_back(c + Vec3(off(rng), off(rng), off(rng)));
    m.triangles.push_back({base, base + 1, base + 2});
  }
  return m;
}

inline TriangleMesh robot_mesh(const std::string& relative) {
  return load_mesh(robots_dir() + "/" + relative);
}

// b's triangles carried into a's frame (the coordinates the BVH queries compare).
inline std::vector<Triangle> carried_triangles(const TriangleMesh& b, const Transform& b_in_a) {
  std::vector<Triangle> tb(b.triangles.size());
  for (std::size_t j = 0; j < tb.size(); ++j) {
    const Triangle t = b.triangle(j);
    tb[j] = Triangle{{b_in_a * t[0], b_in_a * t[1], b_in_a * t[2]}};
  }
  return tb;
}

// A triangle's axis-aligned box: the brute-force oracles' filter, exact (min and max of the
// vertices' own coordinates).
struct TriangleBox {
  Vec3 lo, hi;
  bool apart(const TriangleBox& o) const {
    return (hi.array() < o.lo.array()).any() || (o.hi.array() < lo.array()).any();
  }
  // The squared gap between the boxes, rounded: at most a few ulps above the true one.
  double gap_squared(const TriangleBox& o) const {
    const Vec3 gap = (o.lo - hi).cwiseMax(lo - o.hi).cwiseMax(0.0);
    return gap.squaredNorm();
  }
};

inline TriangleBox triangle_box(const Triangle& t) {
  return {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])};
}

inline std::vector<TriangleBox> triangle_boxes(const std::vector<Triangle>& ts) {
  std::vector<TriangleBox> out;
  out.reserve(ts.size());
  for (const Triangle& t : ts) out.push_back(triangle_box(t));
  return out;
}

// All colliding triangle pairs (mesh indices) by brute force, with b carried into a's frame.
inline std::vector<std::pair<int, int>> brute_force_pairs(const TriangleMesh& a, const TriangleMesh& b,
                                                          const Transform& b_in_a) {
  const std::vector<Triangle> tb = carried_triangles(b, b_in_a);
  const std::vector<TriangleBox> boxes = triangle_boxes(tb);
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < a.triangles.size(); ++i) {
    const Triangle ta = a.triangle(i);
    const TriangleBox box = triangle_box(ta);
    for (std::size_t j = 0; j < tb.size(); ++j) {
      // Boxes of the vertices' own coordinates that are apart (strictly) hold no common point.
      if (box.apart(boxes[j])) continue;
      if (triangles_intersect(ta, tb[j])) out.push_back({static_cast<int>(i), static_cast<int>(j)});
    }
  }
  return out;
}

// Minimum triangle-pair distance by brute force (the same carried coordinates as the BVH uses).
// A pair whose boxes are farther apart than the best distance so far (with a margin for the
// rounding of the boxes' gap) cannot be nearer, and is not measured.
inline double brute_force_distance(const TriangleMesh& a, const TriangleMesh& b, const Transform& b_in_a) {
  double best = std::numeric_limits<double>::infinity();
  const std::vector<Triangle> tb = carried_triangles(b, b_in_a);
  const std::vector<TriangleBox> boxes = triangle_boxes(tb);
  for (std::size_t i = 0; i < a.triangles.size(); ++i) {
    const Triangle ta = a.triangle(i);
    const TriangleBox box = triangle_box(ta);
    for (std::size_t j = 0; j < tb.size(); ++j) {
      if (box.gap_squared(boxes[j]) > best * best * (1 + 1e-9)) continue;
      best = std::min(best, triangle_triangle_distance(ta, tb[j]).distance);
    }
  }
  return best;
}

// A pose of b (in a's frame) near contact: a random orientation, pushed along a random
// direction to where the meshes first touch, then moved by a random relative gap in
// +-[1e-6, 3e-2] of the meshes' size (half of the poses collide, roughly).
inline Transform near_contact_pose(std::mt19937_64& rng, const Bvh<Aabb>& a, const Bvh<Aabb>& b) {
  Transform pose = random_rotation(rng);
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec3 dir = Vec3(n(rng), n(rng), n(rng)).normalized();
  const Vec3 ca = center(a.root().volume), cb = center(b.root().volume);
  const double size = radius(a.root().volume) + radius(b.root().volume);
  auto at = [&](double s) { return Transform{pose.R, ca + dir * s - pose.R * cb}; };
  double lo = 0.0, hi = 2.0 * size;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (collide(a, Transform(), b, at(mid), {0.0, 0.0, 0, false}).collision ? lo : hi) = mid;
  }
  const double gap = std::pow(10.0, std::uniform_real_distribution<double>(-6, std::log10(3e-2))(rng));
  const double sign = std::uniform_int_distribution<int>(0, 1)(rng) ? 1.0 : -1.0;
  return at(hi + sign * gap * size);
}

}  // namespace bvh_collision::test
