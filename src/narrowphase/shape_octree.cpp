#include "bvh_collision/narrowphase/shape_octree.h"

#include <algorithm>
#include <array>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/bvh/traversal.h"
#include "bvh_collision/geometry/traversal_stack.h"
#include "bvh_collision/geometry/tree_walk.h"
#include "bvh_collision/octree/cube_walk.h"
#include "bvh_collision/geometry/convex_distance.h"
#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/intersection.h"

namespace bvh_collision {
namespace {

// The box's surface as 12 triangles: corner i has x from bit 0, y from bit 1, z from bit 2.
std::array<Triangle, 12> box_faces(const Vec3& lo, const Vec3& hi) {
  Vec3 c[8];
  for (int i = 0; i < 8; ++i) c[i] = Vec3(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  static constexpr int quads[6][4] = {{0, 2, 6, 4}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 5, 7, 6}};
  std::array<Triangle, 12> faces;
  for (int f = 0; f < 6; ++f) {
    const int* q = quads[f];
    faces[2 * f] = Triangle{{c[q[0]], c[q[1]], c[q[2]]}};
    faces[2 * f + 1] = Triangle{{c[q[0]], c[q[2]], c[q[3]]}};
  }
  return faces;
}

bool inside_box(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
}

// The gap between the triangle's bounding box and the box along the worst axis (0 if they meet).
double bounds_gap(const Triangle& t, const Vec3& lo, const Vec3& hi) {
  const Vec3 tlo = t[0].cwiseMin(t[1]).cwiseMin(t[2]), thi = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
  return std::max({0.0, (tlo - hi).maxCoeff(), (lo - thi).maxCoeff()});
}

Triangle in_world(const Triangle& t, const Transform& pose) { return Triangle{{pose * t[0], pose * t[1], pose * t[2]}}; }

using Cube = OctreeCube;

// What the descent needs of the octree and the link's pose: a cube as a box in the link frame.
struct CubeFrame {
  const Octree& tree;
  Transform link_from_world;
  Vec3 lo(const Cube& c) const { return tree.cube_min(c.corner); }
  Vec3 hi(const Cube& c) const { return lo(c) + Vec3::Constant(tree.cube_size(c.depth)); }
  Obb box(const Cube& c) const {
    const double half = 0.5 * tree.cube_size(c.depth);
    const Vec3 centre = lo(c) + Vec3::Constant(half);
    return Obb{link_from_world.R, link_from_world * centre, Vec3::Constant(half), half * std::sqrt(3.0)};
  }
  Octree::Leaf leaf(const Cube& c) const { return leaf_of(tree, c); }
  template <class F>
  void for_children(const Cube& c, F&& f, std::uint8_t which = 0xFF) const {
    for_occupied_children(tree, c, std::forward<F>(f), which);
  }
};

// The voxel keys a world box can touch, per axis, as integers: a cube outside them is rejected
// with six comparisons before any separating-axis test. One voxel of margin below, since a cube
// whose upper face touches the box's lower corner has the next key.
struct KeyRange {
  int lo[3], hi[3];
  KeyRange(const OctreeGrid& grid, const Vec3& box_lo, const Vec3& box_hi) {
    for (int i = 0; i < 3; ++i) {
      lo[i] = std::max(0, clamped_key(grid, box_lo[i]) - 1);
      hi[i] = clamped_key(grid, box_hi[i]);
    }
  }
  // The children of the cube (corner, depth) that meet the range, as a mask of child bits b (docs/design.md)
  // (x is bit 2 of b, y bit 1, z bit 0).
  std::uint8_t children(const OctreeKey& corner, int depth) const {
    static constexpr unsigned kHalves[3][2] = {{0x0F, 0xF0}, {0x33, 0xCC}, {0x55, 0xAA}};
    const int half = 1 << (kOctreeDepth - depth - 1);
    unsigned mask = 0xFF;
    for (int i = 0; i < 3; ++i) {
      const int mid = corner.k[i] + half;
      const unsigned low = corner.k[i] <= hi[i] && mid > lo[i] ? kHalves[i][0] : 0u;  // keys [corner, mid)
      const unsigned high = mid <= hi[i] && mid + half > lo[i] ? kHalves[i][1] : 0u;  // [mid, mid + half)
      mask &= low | high;
    }
    return static_cast<std::uint8_t>(mask);
  }
  static int clamped_key(const OctreeGrid& grid, double x) {
    if (const auto k = grid.key(x)) return *k;
    return x < 0.0 ? 0 : 0xFFFF;
  }
};

// A BVH node's box in world axes, carried once per node and query (a node meets many cubes).
struct NodeInWorld {
  Vec3 centre;
  Mat3 axes;         // columns: the box's axes in world
  Vec3 half;
  Vec3 reach;        // half extents of its world-aligned bounding box
  Vec3 axis_spread;  // per box axis, the 1-norm of its world coordinates (a cube's projection)
};

class WorldVolumes {
 public:
  // Looked up once per query: thread_local access costs a call in a shared library.
  static WorldVolumes& for_query(const Bvh<Obb>& mesh, const Transform& pose) {
    thread_local WorldVolumes cache;
    cache.mesh_ = &mesh;
    cache.pose_ = pose;
    ++cache.query_;
    if (cache.stamp_.size() < mesh.nodes().size()) {
      cache.stamp_.resize(mesh.nodes().size(), 0);
      cache.nodes_.resize(mesh.nodes().size());
    }
    return cache;
  }
  const NodeInWorld& operator[](std::int32_t n) {
    if (stamp_[n] != query_) {
      const Obb& v = mesh_->nodes()[n].volume;
      NodeInWorld& w = nodes_[n];
      w.centre = pose_ * v.center;
      w.axes = pose_.R * v.axes;
      w.half = v.half;
      w.reach = w.axes.cwiseAbs() * v.half;
      w.axis_spread = w.axes.cwiseAbs().colwise().sum().transpose();
      stamp_[n] = query_;
    }
    return nodes_[n];
  }

 private:
  const Bvh<Obb>* mesh_ = nullptr;
  Transform pose_;
  std::uint64_t query_ = 0;
  std::vector<std::uint64_t> stamp_;
  std::vector<NodeInWorld> nodes_;
};

// The rounding allowance of the box tests below for one query: a multiple of kVolumeMargin times
// a bound on the magnitudes the tests add up (centres, extents and sizes of every node and cube,
// all inside the two world boxes given), so that rounding never separates boxes that touch.
double rounding_slack(const Vec3& lo, const Vec3& hi, const Vec3& cube_lo, const Vec3& cube_hi) {
  const double b = std::max({lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff(), cube_lo.cwiseAbs().maxCoeff(),
                             cube_hi.cwiseAbs().maxCoeff()});
  return 4.0 * kVolumeMargin * (20.0 * b + 1.0);
}

// Can the node's box come within `reach` (padding plus rounding slack) of the cube (centre c, half
// side h)? The separating axes of both boxes' faces (world axes first: a bounding-box test); the
// nine edge axes are skipped, so the answer may be a conservative yes, never a wrong no. Scalar
// code: this runs for every pair the descent meets.
bool node_meets_cube(const NodeInWorld& n, const Vec3& c, double h, double reach) {
  const double d[3] = {n.centre.x() - c.x(), n.centre.y() - c.y(), n.centre.z() - c.z()};
  const double r = h + reach;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) > n.reach[i] + r) return false;
  }
  for (int j = 0; j < 3; ++j) {
    const double* a = n.axes.col(j).data();
    if (std::abs(a[0] * d[0] + a[1] * d[1] + a[2] * d[2]) > n.half[j] + h * n.axis_spread[j] + reach) return false;
  }
  return true;
}

// The smallest node holding every voxel the box [lo, hi] (world) can touch, found by descending
// while the box's two corner keys fall into the same child (the textbook's box descent): a link's
// query starts there instead of 16 levels above.
std::optional<Cube> start_cube(const Octree& tree, const Vec3& lo, const Vec3& hi) {
  auto cube = occupied_root(tree);
  if (!cube) return cube;
  const auto a = tree.grid().key(lo), b = tree.grid().key(hi);
  if (!a || !b) return cube;
  // One voxel of margin below: a cube whose upper face touches `lo` still matters.
  OctreeKey low = *a;
  for (auto& k : low.k) k = static_cast<std::uint16_t>(k > 0 ? k - 1 : 0);
  while (cube->depth < kOctreeDepth && !tree.is_leaf(cube->node)) {
    const int bit = child_bits(low, cube->depth);
    if (bit != child_bits(*b, cube->depth)) break;
    const std::int32_t child = tree.child(cube->node, bit);
    if (child < 0 || !tree.occupied(tree.value(child))) return std::nullopt;  // nothing occupied there
    *cube = Cube{child, cube->depth + 1, child_corner(cube->corner, cube->depth, bit), child_index(cube->index, bit)};
  }
  return cube;
}

// The world box around a mesh's root volume, grown by `margin`.
std::pair<Vec3, Vec3> world_bounds(const Bvh<Obb>& mesh, const Transform& pose, double margin) {
  const Obb& v = mesh.root().volume;
  const Vec3 centre = pose * v.center;
  const Vec3 half = (pose.R * v.axes).cwiseAbs() * v.half + Vec3::Constant(margin + pose_margin(centre.cwiseAbs().maxCoeff()));
  return {centre - half, centre + half};
}

// Does any occupied leaf inside `cube` meet the key range? Integer work only: a cheap test that
// lets a link in free space skip every box test.
bool occupied_in_range(const CubeFrame& frame, const Cube& cube, const KeyRange& range) {
  bool found = false;
  descend_while(
      frame.tree, cube, [](const Cube&) { return Visit::kEnter; }, [&](const Cube&) { return found = true; },
      [&](const Cube& c) { return range.children(c.corner, c.depth); });
  return found;
}

// Is the cube (centre c, half side h) inside the node's box, up to the rounding slack?
bool cube_within_node(const NodeInWorld& n, const Vec3& c, double h, double slack) {
  const Vec3 d = n.centre - c;
  for (int j = 0; j < 3; ++j) {
    if (std::abs(n.axes.col(j).dot(d)) + h * n.axis_spread[j] > n.half[j] + slack) return false;
  }
  return true;
}

// An occupied leaf cube wholly inside the closed mesh, if there is one. Called after the surface
// test found no occupied leaf meeting a triangle: each such leaf is then wholly inside or wholly
// outside, so its centre decides, and only leaves inside the root volume (which holds the solid)
// need the point-in-mesh test.
std::optional<Cube> cube_inside_solid(const Bvh<Obb>& mesh, const Transform& pose, const CubeFrame& frame,
                                      WorldVolumes& world, QueryStats* stats) {
  if (!mesh.closed()) return std::nullopt;
  const auto [lo, hi] = world_bounds(mesh, pose, 0.0);
  const auto root = start_cube(frame.tree, lo, hi);
  if (!root) return std::nullopt;
  const KeyRange range(frame.tree.grid(), lo, hi);
  const double slack = rounding_slack(lo, hi, frame.lo(*root), frame.hi(*root));
  const NodeInWorld& volume = world[0];
  std::optional<Cube> inside;
  auto visit = [&](const Cube& c) {
    const double half = 0.5 * frame.tree.cube_size(c.depth);
    return node_meets_cube(volume, frame.lo(c) + Vec3::Constant(half), half, slack) ? Visit::kEnter : Visit::kSkip;
  };
  auto leaf = [&](const Cube& c) {
    const double half = 0.5 * frame.tree.cube_size(c.depth);
    const Vec3 centre = frame.lo(c) + Vec3::Constant(half);
    if (cube_within_node(volume, centre, half, slack) && contains_point(mesh, frame.link_from_world * centre, stats)) inside = c;
    return inside.has_value();
  };
  descend_while(frame.tree, *root, visit, leaf, [&](const Cube& c) { return range.children(c.corner, c.depth); });
  return inside;
}

}  // namespace

bool triangle_meets_box(const Triangle& t, const Vec3& lo, const Vec3& hi) {
  if (bounds_gap(t, lo, hi) > 0.0) return false;
  for (int k = 0; k < 3; ++k) {
    if (inside_box(t[k], lo, hi)) return true;
  }
  // No vertex inside: the triangle meets the box only by crossing its surface (a box edge through
  // the triangle or a triangle edge through a face), which the exact triangle tests decide.
  for (const Triangle& f : box_faces(lo, hi)) {
    if (triangles_intersect(t, f)) return true;
  }
  return false;
}

double triangle_box_distance(const Triangle& t, const Vec3& lo, const Vec3& hi, Vec3& on_triangle, Vec3& on_box) {
  for (int k = 0; k < 3; ++k) {
    if (inside_box(t[k], lo, hi)) {
      on_triangle = on_box = t[k];
      return 0.0;
    }
  }
  double best = std::numeric_limits<double>::infinity();
  for (const Triangle& f : box_faces(lo, hi)) {
    if (triangles_intersect(t, f)) {
      on_triangle = on_box = intersection_point(t, f);
      return 0.0;
    }
    const ClosestPoints c = triangle_triangle_distance(t, f);
    if (c.distance < best) {
      best = c.distance;
      on_triangle = c.on_a;
      on_box = c.on_b;
    }
  }
  return best;
}

bool mesh_meets_octree(const Bvh<Obb>& mesh, const Transform& pose, const Octree& tree, double padding,
                       double tolerance, bool solids, OctreeContact* contact, QueryStats* stats) {
  if (mesh.empty()) return false;
  const auto [reach_lo, reach_hi] = world_bounds(mesh, pose, padding);  // a tolerance only settles sooner
  const auto root = start_cube(tree, reach_lo, reach_hi);
  if (!root) return false;
  QueryStats local;
  QueryStats& s = stats ? *stats : local;
  const CubeFrame frame{tree, pose.inverse()};
  const auto& nodes = mesh.nodes();
  const KeyRange reach(tree.grid(), reach_lo, reach_hi);
  if (!occupied_in_range(frame, *root, reach)) return false;
  const double allowance = padding + rounding_slack(reach_lo, reach_hi, frame.lo(*root), frame.hi(*root));
  WorldVolumes& world = WorldVolumes::for_query(mesh, pose);
  bool hit = false;
  depth_first_pair_walk(
      OccupiedCubeView<>{tree, {}}, BvhView<Obb>{mesh, LeftFirst{}}, *root, std::int32_t{0},
      [&](const Cube& cube, std::int32_t node) {
        const BvhNode<Obb>& n = nodes[node];
        const double half = 0.5 * tree.cube_size(cube.depth);
        ++s.volume_tests;
        if (!node_meets_cube(world[node], frame.lo(cube) + Vec3::Constant(half), half, allowance)) return Visit::kSkip;
        // Every point of the volume lies within `slack` of the node's triangles, so a volume within
        // padding of the cube puts a triangle within padding + slack of it: allowed by the tolerance.
        // (Only against a leaf: an inner cube is "occupied" when some cube inside it is.) The test
        // above skips the nine edge axes, so it may pass boxes that are far apart edge to edge: the
        // shortcut takes all fifteen axes (overlap_carried), whose rounding allowance is counted too.
        const bool settled = tree.is_leaf(cube.node) && tolerance > 0.0 && n.slack + kPoseMargin * (n.size + half) <= tolerance &&
                             overlap_carried(n.volume, frame.box(cube), padding);
        if (!settled) return Visit::kEnter;
        if (contact) *contact = {frame.leaf(cube), pose * n.volume.center};
        hit = true;
        return Visit::kStop;
      },
      [&](const Cube& cube, std::int32_t node) {  // a leaf cube and a leaf node: their triangles
        const BvhNode<Obb>& n = nodes[node];
        const Vec3 lo = frame.lo(cube), hi = frame.hi(cube);
        for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
          const Triangle t = in_world(mesh.triangles()[i], pose);
          ++s.primitive_tests;
          Vec3 on_t, on_b;
          hit = padding > 0.0 ? bounds_gap(t, lo, hi) <= padding && triangle_box_distance(t, lo, hi, on_t, on_b) <= padding
                              : triangle_meets_box(t, lo, hi);
          if (hit) {
            if (contact) *contact = {frame.leaf(cube), padding > 0.0 ? on_t : t[0]};
            return true;
          }
        }
        return false;
      },
      [&](const Cube& cube, std::int32_t node, auto&& push) {
        // Descend the larger of the two (a leaf cannot be descended).
        const BvhNode<Obb>& n = nodes[node];
        if (!tree.is_leaf(cube.node) && (n.is_leaf() || std::sqrt(3.0) * 0.5 * tree.cube_size(cube.depth) > n.size)) {
          frame.for_children(cube, [&](const Cube& c) { push(c, node); }, reach.children(cube.corner, cube.depth));
        } else {
          push(cube, n.right);
          push(cube, n.left);
        }
      });
  if (hit) return true;
  if (!solids) return false;
  if (const auto inside = cube_inside_solid(mesh, pose, frame, world, &s)) {
    if (contact) *contact = {frame.leaf(*inside), pose * frame.box(*inside).center};
    return true;
  }
  return false;
}

OctreeDistance mesh_octree_distance(const Bvh<Obb>& mesh, const Transform& pose, const Octree& tree, bool solids,
                                    double upper_bound, QueryStats* stats) {
  OctreeDistance best;
  const auto root = occupied_root(tree);
  if (!root || mesh.empty()) return best;
  QueryStats local;
  QueryStats& s = stats ? *stats : local;
  const CubeFrame frame{tree, pose.inverse()};
  const auto& nodes = mesh.nodes();
  const RelativeFrame same;  // cubes are already carried into the link frame
  double bound = upper_bound;
  nearest_first_pair_walk(
      OccupiedCubeView<>{tree, {}}, BvhView<Obb>{mesh, LeftFirst{}}, *root, std::int32_t{0}, 0.0,
      [&](const Cube& c, std::int32_t node) {
        ++s.volume_tests;
        return distance_lower_bound(nodes[node].volume, frame.box(c), same);
      },
      [&](const Cube& cube, std::int32_t node) {  // a leaf cube and a leaf node: their triangles
        const BvhNode<Obb>& n = nodes[node];
        const Vec3 lo = frame.lo(cube), hi = frame.hi(cube);
        for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
          const Triangle t = in_world(mesh.triangles()[i], pose);
          if (bounds_gap(t, lo, hi) >= bound) continue;
          ++s.primitive_tests;
          Vec3 on_t, on_b;
          const double d = triangle_box_distance(t, lo, hi, on_t, on_b);
          if (d < bound) {
            bound = d;
            best = {d, on_t, on_b, frame.leaf(cube)};
          }
        }
        return false;
      },
      [&](const Cube& cube, std::int32_t node, auto&& push) {
        // Descend the larger of the two (a leaf cannot be descended).
        const BvhNode<Obb>& n = nodes[node];
        if (!tree.is_leaf(cube.node) && (n.is_leaf() || 0.5 * std::sqrt(3.0) * tree.cube_size(cube.depth) > n.size)) {
          frame.for_children(cube, [&](const Cube& c) { push(c, node); });
        } else {
          push(cube, n.left);
          push(cube, n.right);
        }
      },
      [&] { return bound; });
  if (solids && best.distance > 0.0) {
    if (const auto inside = cube_inside_solid(mesh, pose, frame, WorldVolumes::for_query(mesh, pose), &s)) {
      const Vec3 centre = pose * frame.box(*inside).center;
      best = {0.0, centre, centre, frame.leaf(*inside)};
    }
  }
  return best;
}

OctreeDistance point_octree_distance(const Vec3& p, const Octree& tree, double upper_bound) {
  OctreeDistance best;
  const auto root = occupied_root(tree);
  if (!root) return best;
  const CubeFrame frame{tree, Transform::Identity()};
  double bound = upper_bound;
  auto lower = [&](const Cube& c) { return (p - p.cwiseMax(frame.lo(c)).cwiseMin(frame.hi(c))).norm(); };
  auto leaf = [&](const Cube& c) {
    const Vec3 nearest = p.cwiseMax(frame.lo(c)).cwiseMin(frame.hi(c));
    bound = (p - nearest).norm();
    best = {bound, p, nearest, frame.leaf(c)};
    return false;
  };
  nearest_cubes_first(tree, *root, lower, leaf, [&] { return bound; });
  return best;
}

namespace {

// A primitive as the octree descent sees it: its box in world axes, and the cube against it.
struct PrimitiveInWorld {
  const Primitive& primitive;
  const Transform& pose;
  NodeInWorld box;
  PrimitiveInWorld(const Primitive& p, const Transform& pose_) : primitive(p), pose(pose_) {
    box.centre = pose.t;
    box.axes = pose.R;
    box.half = half_extents(p);
    box.reach = pose.R.cwiseAbs() * box.half;
    box.axis_spread = pose.R.cwiseAbs().colwise().sum().transpose();
  }
  // The cube (centre c, half side h, world) against the primitive, in the primitive's frame.
  ConvexDistance against(const Vec3& c, double h, double decide_at) const {
    const Transform cube_in_primitive{pose.R.transpose(), pose.R.transpose() * (c - pose.t)};
    return convex_distance(ConvexShape::of(primitive), ConvexShape::of(Primitive::box(Vec3::Constant(2 * h))),
                           cube_in_primitive, decide_at);
  }
};

}  // namespace

bool primitive_meets_octree(const Primitive& primitive, const Transform& pose, const Octree& tree, double padding,
                            OctreeContact* contact, QueryStats* stats) {
  const PrimitiveInWorld shape(primitive, pose);
  const double margin = padding + pose_margin(pose.t.cwiseAbs().maxCoeff());
  const Vec3 lo = pose.t - shape.box.reach - Vec3::Constant(margin), hi = pose.t + shape.box.reach + Vec3::Constant(margin);
  const auto start = start_cube(tree, lo, hi);
  if (!start) return false;
  const CubeFrame frame{tree, pose.inverse()};
  const KeyRange range(tree.grid(), lo, hi);
  const double slack = padding + rounding_slack(lo, hi, frame.lo(*start), frame.hi(*start));
  bool met = false;
  auto visit = [&](const Cube& c) {
    const double half = 0.5 * tree.cube_size(c.depth);
    if (stats) ++stats->volume_tests;
    return node_meets_cube(shape.box, frame.lo(c) + Vec3::Constant(half), half, slack) ? Visit::kEnter : Visit::kSkip;
  };
  auto leaf = [&](const Cube& c) {
    const double half = 0.5 * tree.cube_size(c.depth);
    if (stats) ++stats->primitive_tests;
    const ConvexDistance d = shape.against(frame.lo(c) + Vec3::Constant(half), half, padding);
    if (d.lower_bound > padding) return false;
    if (contact) *contact = {frame.leaf(c), pose * (0.5 * (d.on_a + d.on_b))};
    return met = true;
  };
  descend_while(tree, *start, visit, leaf, [&](const Cube& c) { return range.children(c.corner, c.depth); });
  return met;
}

OctreeDistance primitive_octree_distance(const Primitive& primitive, const Transform& pose, const Octree& tree,
                                         double upper_bound, QueryStats* stats) {
  OctreeDistance best;
  const auto root = occupied_root(tree);
  if (!root) return best;
  const PrimitiveInWorld shape(primitive, pose);
  const CubeFrame frame{tree, pose.inverse()};
  const Vec3 half = half_extents(primitive);
  const Obb own{Mat3::Identity(), Vec3::Zero(), half, half.norm()};
  const RelativeFrame same = RelativeFrame::from(Transform::Identity());
  double bound = upper_bound;
  auto lower = [&](const Cube& c) {
    if (stats) ++stats->volume_tests;
    return distance_lower_bound(own, frame.box(c), same);
  };
  auto leaf = [&](const Cube& c) {
    if (stats) ++stats->primitive_tests;
    const double h = 0.5 * tree.cube_size(c.depth);
    const ConvexDistance d = shape.against(frame.lo(c) + Vec3::Constant(h), h, std::numeric_limits<double>::quiet_NaN());
    const double dist = d.intersecting ? 0.0 : d.distance;
    if (dist < bound) {
      bound = dist;
      const Vec3 on_link = pose * d.on_a, on_cube = d.intersecting ? on_link : Vec3(pose * d.on_b);
      best = {dist, on_link, on_cube, frame.leaf(c)};
    }
    return false;
  };
  nearest_cubes_first(tree, *root, lower, leaf, [&] { return bound; });
  return best;
}

// ---- The dispatch over the shape's kind ----------------------------------------------------------

bool shape_meets_octree(const ShapeRef& shape, const Transform& pose, const Octree& tree, const PairRequest& request,
                        OctreeContact* contact, QueryStats& stats) {
  const double padding = request.padding;
  if (shape.mesh != nullptr) {
    return mesh_meets_octree(*shape.mesh, pose, tree, padding, request.tolerance, request.solids, contact, &stats);
  }
  if (shape.primitive.kind != Primitive::Kind::kSphere) return primitive_meets_octree(shape.primitive, pose, tree, padding, contact, &stats);
  const auto cubes = tree.occupied_in_sphere(pose.t, shape.primitive.radius + padding, true);
  if (cubes.empty()) return false;
  if (contact != nullptr) {
    const Vec3 lo = tree.cube_min(cubes.front().key), hi = lo + Vec3::Constant(tree.cube_size(cubes.front().depth));
    *contact = {cubes.front(), pose.t.cwiseMax(lo).cwiseMin(hi)};
  }
  return true;
}

OctreeDistance shape_octree_distance(const ShapeRef& shape, const Transform& pose, const Octree& tree, bool solids,
                                     double upper_bound, QueryStats& stats) {
  if (shape.mesh != nullptr) return mesh_octree_distance(*shape.mesh, pose, tree, solids, upper_bound, &stats);
  if (shape.primitive.kind != Primitive::Kind::kSphere) return primitive_octree_distance(shape.primitive, pose, tree, upper_bound, &stats);
  // A sphere is its centre with the radius taken off: the surface point towards the cube, or
  // inside the sphere the cube point itself.
  const double radius = shape.primitive.radius;
  OctreeDistance d = point_octree_distance(pose.t, tree, upper_bound + radius);
  if (std::isfinite(d.distance)) {
    const double gap = d.distance - radius;
    d.on_link = gap > 0 ? Vec3(pose.t + (d.on_cube - pose.t) * (radius / d.distance)) : d.on_cube;
    d.distance = std::max(0.0, gap);
  }
  return d;
}

}  // namespace bvh_collision
