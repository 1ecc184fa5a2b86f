// A bounding volume hierarchy over a triangle mesh: a flat array of nodes with child indices,
// leaves indexing a triangle array stored in leaf order (so a leaf's triangles are contiguous).
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "bvh_collision/bvh/bounding_volumes.h"
#include "bvh_collision/geometry/mesh.h"
#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision {

enum class BuildMethod {
  kTopDownMedian,  // the textbook's: split at the centre of the longest axis, by triangle centroid
  kSah,            // binned surface area heuristic
  kBottomUp,       // agglomerative: repeatedly merge the closest pair of clusters
};

const char* build_method_name(BuildMethod m);

struct BuildOptions {
  BuildMethod method = BuildMethod::kSah;  // fewest volume tests in the benchmark
  int max_leaf_triangles = 1;
  int max_depth = 64;  // top-down builders: a node this deep becomes a leaf
  // Each node's slack bounded by sampling its volume (the tightest proven bound; most of a small
  // mesh's build), or only by its corners and its children's (looser, proven all the same): a
  // collision object's box answers single states as the exact primitive, and a scene holds
  // thousands of them.
  bool sampled_slack = true;
};

template <class BV>
struct BvhNode {
  BV volume;
  double size = 0.0;   // radius(volume): the larger of two volumes is descended first
  double slack = 0.0;  // every point of `volume` lies within `slack` of this node's triangles
  std::int32_t left = -1, right = -1;  // children; -1 for a leaf
  std::int32_t first = 0, count = 0;   // this subtree's triangles: [first, first + count)
  bool is_leaf() const { return left < 0; }
};

// A triangle's bounding sphere (centroid, largest vertex distance): a cheap distance bound.
struct TriangleSphere {
  Vec3 center = Vec3::Zero();
  double radius = 0.0;
  static TriangleSphere of(const Triangle& t) {
    TriangleSphere s;
    s.center = (t[0] + t[1] + t[2]) / 3.0;
    s.radius = std::max({(t[0] - s.center).norm(), (t[1] - s.center).norm(), (t[2] - s.center).norm()});
    return s;
  }
};

template <class BV>
class Bvh {
 public:
  Bvh() = default;
  static Bvh build(const TriangleMesh& mesh, const BuildOptions& options = {});

  const std::vector<BvhNode<BV>>& nodes() const { return nodes_; }
  const BvhNode<BV>& root() const { return nodes_.front(); }
  // Triangles in leaf order, and each one's index in the mesh it was built from.
  const std::vector<Triangle>& triangles() const { return triangles_; }
  std::int32_t triangle_id(std::size_t leaf_order_index) const { return triangle_ids_[leaf_order_index]; }
  // Per triangle (leaf order): its plane for certified side tests, and its bounding sphere.
  const std::vector<TrianglePlane>& planes() const { return planes_; }
  const std::vector<TriangleSphere>& spheres() const { return spheres_; }
  // A closed, consistently oriented mesh: the hierarchy stands for the solid it bounds.
  bool closed() const { return closed_; }
  // The build's work bounding the slack: point-triangle distances taken (sampled for small
  // meshes, corners for large ones); a test bounds it, so a large mesh never takes the small path.
  std::uint64_t slack_evaluations() const { return slack_evaluations_; }
  // One vertex of each connected component (see component_representatives()).
  const std::vector<Vec3>& component_points() const { return component_points_; }
  bool empty() const { return nodes_.empty(); }
  std::size_t memory_bytes() const;
  int depth() const;

 private:
  std::vector<BvhNode<BV>> nodes_;
  std::vector<Triangle> triangles_;
  std::vector<std::int32_t> triangle_ids_;
  std::vector<TrianglePlane> planes_;
  std::vector<TriangleSphere> spheres_;
  std::vector<Vec3> component_points_;
  std::uint64_t slack_evaluations_ = 0;
  bool closed_ = false;

  template <class T>
  friend struct BvhBuilder;
};

extern template class Bvh<Aabb>;
extern template class Bvh<Obb>;
extern template class Bvh<Sphere>;
extern template class Bvh<Kdop14>;
extern template class Bvh<Kdop18>;
extern template class Bvh<Kdop26>;
extern template class Bvh<Rss>;

}  // namespace bvh_collision
