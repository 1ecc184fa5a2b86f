#include "bvh_collision/bvh/bvh.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <numeric>
#include <thread>
#include <type_traits>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/tree_walk.h"

namespace bvh_collision {

const char* build_method_name(BuildMethod m) {
  switch (m) {
    case BuildMethod::kTopDownMedian: return "top-down median";
    case BuildMethod::kSah: return "SAH";
    case BuildMethod::kBottomUp: return "bottom-up";
  }
  return "?";
}

namespace {

struct Prim {
  Aabb box;
  Vec3 centroid;
};

double half_area(const Aabb& b) {
  const Vec3 e = b.max - b.min;
  return e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
}

int longest_axis(const Vec3& extent) {
  int axis = 0;
  extent.maxCoeff(&axis);
  return axis;
}

using Order = std::vector<std::int32_t>;

// Meshes up to this many triangles (robot links, most objects) get the build's most expensive
// refinements: the rotation search for boxes and sampled slack. Larger ones (a 400k-triangle
// scan) get boxes from principal axes and slack from corners and children, both still exact
// bounds, so that they load in about a second.
constexpr std::size_t kSearchedMesh = 50000;
// Meshes over this many triangles build (and bound) the root's two subtrees on two threads.
constexpr std::size_t kParallelBuild = 20000;

// Split at the median centroid along the widest centroid axis (always splits when n >= 2).
int split_at_median(Order& order, int begin, int end, const std::vector<Prim>& prims) {
  Aabb cb;
  for (int i = begin; i < end; ++i) cb.extend(prims[order[i]].centroid);
  const int axis = longest_axis(cb.max - cb.min);
  const int mid = begin + (end - begin) / 2;
  std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                   [&](std::int32_t a, std::int32_t b) { return prims[a].centroid[axis] < prims[b].centroid[axis]; });
  return mid;
}

// The textbook's split: the plane through the centre of the longest axis of the node's box,
// triangles assigned by centroid. Falls back to the median when one side would be empty.
int split_at_centre(Order& order, int begin, int end, const std::vector<Prim>& prims) {
  Aabb box;
  for (int i = begin; i < end; ++i) box = merge(box, prims[order[i]].box);
  const int axis = longest_axis(box.max - box.min);
  const double plane = center(box)[axis];
  const auto it = std::partition(order.begin() + begin, order.begin() + end,
                                 [&](std::int32_t t) { return prims[t].centroid[axis] < plane; });
  const int mid = static_cast<int>(it - order.begin());
  return (mid == begin || mid == end) ? split_at_median(order, begin, end, prims) : mid;
}

// Binned SAH over the centroid bounds (16 bins per axis).
int split_by_sah(Order& order, int begin, int end, const std::vector<Prim>& prims) {
  constexpr int kBins = 16;
  Aabb cb;
  for (int i = begin; i < end; ++i) cb.extend(prims[order[i]].centroid);
  double best_cost = std::numeric_limits<double>::infinity();
  int best_axis = -1, best_bin = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const double lo = cb.min[axis], extent = cb.max[axis] - lo;
    if (!(extent > 0.0)) continue;
    Aabb boxes[kBins];
    int counts[kBins] = {};
    for (int i = begin; i < end; ++i) {
      const Prim& p = prims[order[i]];
      const int b = std::min(kBins - 1, static_cast<int>(kBins * (p.centroid[axis] - lo) / extent));
      boxes[b] = merge(boxes[b], p.box);
      ++counts[b];
    }
    double right_cost[kBins] = {};
    Aabb acc;
    int n = 0;
    for (int b = kBins - 1; b > 0; --b) {
      acc = merge(acc, boxes[b]);
      n += counts[b];
      right_cost[b] = n ? half_area(acc) * n : 0.0;
    }
    acc = Aabb();
    n = 0;
    for (int b = 0; b < kBins - 1; ++b) {
      acc = merge(acc, boxes[b]);
      n += counts[b];
      const double cost = (n ? half_area(acc) * n : 0.0) + right_cost[b + 1];
      if (n > 0 && n < end - begin && cost < best_cost) {
        best_cost = cost;
        best_axis = axis;
        best_bin = b;
      }
    }
  }
  if (best_axis < 0) return split_at_median(order, begin, end, prims);
  const double lo = cb.min[best_axis], extent = cb.max[best_axis] - lo;
  const auto it = std::partition(order.begin() + begin, order.begin() + end, [&](std::int32_t t) {
    const int b = std::min(kBins - 1, static_cast<int>(kBins * (prims[t].centroid[best_axis] - lo) / extent));
    return b <= best_bin;
  });
  const int mid = static_cast<int>(it - order.begin());
  return (mid == begin || mid == end) ? split_at_median(order, begin, end, prims) : mid;
}

std::uint32_t spread_bits(std::uint32_t v) {  // 10 bits -> every third bit
  v = (v * 0x00010001u) & 0xFF0000FFu;
  v = (v * 0x00000101u) & 0x0F00F00Fu;
  v = (v * 0x00000011u) & 0xC30C30C3u;
  v = (v * 0x00000005u) & 0x49249249u;
  return v;
}

}  // namespace

template <class BV>
struct BvhBuilder {
  struct SharedInput {};
  const TriangleMesh& mesh;
  BuildOptions options;
  std::vector<Prim> own_prims;
  Order own_order;
  std::vector<Prim>& prims;  // the builder's own, or (SharedInput) another builder's
  Order& order;
  std::vector<Vec3> scratch;
  std::vector<std::uint32_t> last_fit;  // per vertex: the fit() call that last took it
  // Point-triangle distances taken to bound the slack (the two halves of a large tree add at once).
  mutable std::atomic<std::uint64_t> evaluations{0};
  std::uint32_t fit_round = 0;
  Bvh<BV> out;

  BvhBuilder(const BvhBuilder&) = delete;
  BvhBuilder& operator=(const BvhBuilder&) = delete;
  // A second builder over the same triangles and order, for a subtree of its own.
  BvhBuilder(BvhBuilder& other, SharedInput)
      : mesh(other.mesh), options(other.options), prims(other.prims), order(other.order), last_fit(mesh.vertices.size(), 0) {}

  BvhBuilder(const TriangleMesh& m, const BuildOptions& o)
      : mesh(m), options(o), prims(own_prims), order(own_order), last_fit(m.vertices.size(), 0) {
    prims.resize(mesh.triangles.size());
    for (std::size_t i = 0; i < prims.size(); ++i) {
      const Triangle t = mesh.triangle(i);
      for (int k = 0; k < 3; ++k) prims[i].box.extend(t[k]);
      prims[i].centroid = (t[0] + t[1] + t[2]) / 3.0;
    }
  }

  // The volume fitted to the vertices of triangles order[begin, end), each vertex once: in a
  // closed mesh a vertex is shared by about six triangles, so this fits a sixth of the points.
  BV fit(int begin, int end) {
    scratch.clear();
    ++fit_round;
    for (int i = begin; i < end; ++i) {
      for (const std::int32_t v : mesh.triangles[order[i]]) {
        if (last_fit[v] == fit_round) continue;
        last_fit[v] = fit_round;
        scratch.push_back(mesh.vertices[v]);
      }
    }
    if constexpr (std::is_same_v<BV, Obb>) {
      return fit_obb(scratch.data(), scratch.size(), mesh.triangles.size() <= kSearchedMesh);
    } else {
      return fit_volume<BV>(scratch.data(), scratch.size());
    }
  }

  std::int32_t new_node(int begin, int end) {
    BvhNode<BV> node;
    node.first = begin;
    node.count = end - begin;
    out.nodes_.push_back(node);
    return static_cast<std::int32_t>(out.nodes_.size() - 1);
  }

  std::int32_t top_down(int begin, int end, int depth) {
    const std::int32_t idx = new_node(begin, end);
    out.nodes_[idx].volume = fit(begin, end);
    if (end - begin <= options.max_leaf_triangles || depth >= options.max_depth) return idx;
    const int mid = options.method == BuildMethod::kSah ? split_by_sah(order, begin, end, prims)
                                                        : split_at_centre(order, begin, end, prims);
    const std::int32_t left = top_down(begin, mid, depth + 1);
    const std::int32_t right = top_down(mid, end, depth + 1);
    out.nodes_[idx].left = left;
    out.nodes_[idx].right = right;
    return idx;
  }

  // ---- bottom-up: locally-ordered agglomerative clustering over Morton-sorted centroids.
  struct Cluster {
    Aabb box;
    std::int32_t left = -1, right = -1, triangle = -1, count = 1;
  };

  std::vector<Cluster> agglomerate() {
    std::vector<Cluster> tree(prims.size());
    Aabb cb;
    for (const Prim& p : prims) cb.extend(p.centroid);
    const Vec3 extent = (cb.max - cb.min).cwiseMax(Vec3::Constant(1e-300));
    std::vector<std::pair<std::uint32_t, std::int32_t>> keyed(prims.size());
    for (std::size_t i = 0; i < prims.size(); ++i) {
      tree[i].box = prims[i].box;
      tree[i].triangle = static_cast<std::int32_t>(i);
      const Vec3 u = ((prims[i].centroid - cb.min).cwiseQuotient(extent) * 1023.0).cwiseMax(0.0).cwiseMin(1023.0);
      keyed[i] = {spread_bits(u.x()) << 2 | spread_bits(u.y()) << 1 | spread_bits(u.z()), static_cast<std::int32_t>(i)};
    }
    std::sort(keyed.begin(), keyed.end());
    std::vector<std::int32_t> live(keyed.size());
    for (std::size_t i = 0; i < keyed.size(); ++i) live[i] = keyed[i].second;
    while (live.size() > 1) live = merge_round(tree, live);
    tree.push_back(tree[live[0]]);  // the root, last
    return tree;
  }

  // One round: every cluster finds its nearest neighbour (smallest merged box) within a window
  // of the order; mutual nearest pairs merge.
  std::vector<std::int32_t> merge_round(std::vector<Cluster>& tree, const std::vector<std::int32_t>& live) {
    constexpr int kWindow = 8;
    const int n = static_cast<int>(live.size());
    std::vector<int> nearest(n, -1);
    for (int i = 0; i < n; ++i) {
      double best = std::numeric_limits<double>::infinity();
      for (int j = std::max(0, i - kWindow); j <= std::min(n - 1, i + kWindow); ++j) {
        if (j == i) continue;
        const double cost = half_area(merge(tree[live[i]].box, tree[live[j]].box));
        if (cost < best) {
          best = cost;
          nearest[i] = j;
        }
      }
    }
    std::vector<std::int32_t> next;
    for (int i = 0; i < n; ++i) {
      const int j = nearest[i];
      if (nearest[j] != i) {
        next.push_back(live[i]);
      } else if (i < j) {
        Cluster c;
        c.box = merge(tree[live[i]].box, tree[live[j]].box);
        c.left = live[i];
        c.right = live[j];
        c.count = tree[live[i]].count + tree[live[j]].count;
        tree.push_back(c);
        next.push_back(static_cast<std::int32_t>(tree.size() - 1));
      }
    }
    return next;
  }

  void collect(const std::vector<Cluster>& tree, std::int32_t c) {
    if (tree[c].triangle >= 0) {
      order.push_back(tree[c].triangle);
      return;
    }
    collect(tree, tree[c].left);
    collect(tree, tree[c].right);
  }

  // Emits the cluster tree as nodes; small subtrees become leaves. Inner volumes are merges of
  // their children's (the textbook's bottom-up update); leaves are fitted.
  std::int32_t emit(const std::vector<Cluster>& tree, std::int32_t c) {
    const int begin = static_cast<int>(order.size());
    const std::int32_t idx = new_node(begin, begin);
    if (tree[c].count <= options.max_leaf_triangles) {
      collect(tree, c);
      out.nodes_[idx].volume = fit(begin, static_cast<int>(order.size()));
    } else {
      const std::int32_t left = emit(tree, tree[c].left);
      const std::int32_t right = emit(tree, tree[c].right);
      out.nodes_[idx].left = left;
      out.nodes_[idx].right = right;
      out.nodes_[idx].volume = merge(out.nodes_[left].volume, out.nodes_[right].volume);
    }
    out.nodes_[idx].count = static_cast<int>(order.size()) - begin;
    return idx;
  }

  // Slack: the largest distance from a point of the volume to the node's triangles. Both bounds
  // below take the largest of a 1-Lipschitz function over the centres of 4x4x4 cells of an
  // enclosing box and add the cell's half diagonal, so each is an upper bound, not an estimate:
  //  - sampled: the distance to the node's own triangles (64 x count work, so only for nodes of
  //    up to kMaxSampled triangles, and not at all on meshes over kSearchedMesh);
  //  - composed: min over the children of (distance to the child's box + the child's slack),
  //    which every point of the parent satisfies since the child's triangles are the parent's.
  // Nodes come parent first (pre-order), so a reverse pass sees children before parents.
  static constexpr int kCells = 4;

  template <class Distance>
  static double lipschitz_max(const EnclosingBox& box, Distance&& distance) {
    double worst = 0.0;
    for (int i = 0; i < kCells * kCells * kCells; ++i) {
      const Vec3 u((i % kCells + 0.5) / kCells, (i / kCells % kCells + 0.5) / kCells, (i / (kCells * kCells) + 0.5) / kCells);
      worst = std::max(worst, distance(box.center + box.axes * (box.half.cwiseProduct(2.0 * u - Vec3::Ones())), worst));
    }
    return (worst + box.half.norm() / kCells) * (1 + kPoseMargin);
  }

  double sampled_slack(const EnclosingBox& box, const BvhNode<BV>& node) const {
    std::uint64_t evaluated = 0;
    const double bound = lipschitz_max(box, [&](const Vec3& s, double worst) {
      double best = std::numeric_limits<double>::infinity();
      for (int t = node.first; t < node.first + node.count && best > worst; ++t, ++evaluated) {
        const Triangle& tri = out.triangles_[t];
        best = std::min(best, (closest_point_on_triangle(s, tri[0], tri[1], tri[2]) - s).norm());
      }
      return best;  // stopping at or below `worst` cannot raise the maximum
    });
    evaluations += evaluated;
    return bound;
  }

  // A node of few triangles: the distance to one triangle is convex, so over a box it is largest
  // at a corner; the smallest such corner maximum over the node's triangles bounds the node
  // (exactly, for a single triangle).
  // `to_vertices`: the distance to the triangle's nearest vertex instead (no less than the
  // distance to the triangle, so still a bound; a tenth of the work, for very large meshes).
  double corner_slack(const EnclosingBox& box, const BvhNode<BV>& node, bool to_vertices) const {
    double best = std::numeric_limits<double>::infinity();
    std::uint64_t evaluated = 0;
    for (int t = node.first; t < node.first + node.count; ++t) {
      const Triangle& tri = out.triangles_[t];
      double worst = 0.0;
      for (int c = 0; c < 8 && worst < best; ++c, ++evaluated) {
        const Vec3 corner = box.center + box.axes * Vec3(c & 1 ? box.half.x() : -box.half.x(),
                                                         c & 2 ? box.half.y() : -box.half.y(),
                                                         c & 4 ? box.half.z() : -box.half.z());
        const double d = to_vertices ? std::sqrt(std::min({(tri[0] - corner).squaredNorm(), (tri[1] - corner).squaredNorm(),
                                                            (tri[2] - corner).squaredNorm()}))
                                     : (closest_point_on_triangle(corner, tri[0], tri[1], tri[2]) - corner).norm();
        worst = std::max(worst, d);
      }
      best = std::min(best, worst);
    }
    evaluations += evaluated;
    return best * (1 + kPoseMargin);
  }

  // `box_slack`: each node's slack over its whole enclosing box (which may be larger than the
  // volume, e.g. a sphere's), the quantity composition needs from the children.
  // The sample points are s = centre + axes * (half .* (2u - 1)) on the 4x4x4 grid, so each
  // child's box coordinates of s are linear in the grid indices: a base and three steps per
  // child, not a matrix product per sample (this pass visits every node of the tree).
  double composed_slack(const EnclosingBox& box, const BvhNode<BV>& node, const std::vector<double>& box_slack) const {
    struct ChildFrame {
      Vec3 base, step[3], half;
      double slack;
    };
    ChildFrame frames[2];
    const std::int32_t children[2] = {node.left, node.right};
    for (int c = 0; c < 2; ++c) {
      const EnclosingBox child = enclosing_box(out.nodes_[children[c]].volume);
      const Mat3 to_child = child.axes.transpose() * box.axes;
      const Vec3 first = box.half * ((0.5 / kCells) * 2.0 - 1.0);  // the grid's first centre, in box axes
      frames[c].base = child.axes.transpose() * (box.center - child.center) + to_child * first;
      for (int k = 0; k < 3; ++k) frames[c].step[k] = to_child.col(k) * (2.0 * box.half[k] / kCells);
      frames[c].half = child.half;
      frames[c].slack = box_slack[children[c]];
    }
    double worst = 0.0;
    for (int i = 0; i < kCells * kCells * kCells; ++i) {
      const int ix = i % kCells, iy = i / kCells % kCells, iz = i / (kCells * kCells);
      double best = std::numeric_limits<double>::infinity();
      for (const ChildFrame& f : frames) {
        const Vec3 local = f.base + ix * f.step[0] + iy * f.step[1] + iz * f.step[2];
        best = std::min(best, (local.cwiseAbs() - f.half).cwiseMax(0.0).norm() + f.slack);
        if (best <= worst) break;  // the minimum can only fall: it cannot raise the maximum
      }
      worst = std::max(worst, best);
    }
    return (worst + box.half.norm() / kCells) * (1 + kPoseMargin);
  }

  // Nodes [begin, end) in reverse: a whole subtree (or several) and nothing that hangs below
  // another part of the tree, so two such ranges can run at once.
  void compute_slack(std::size_t begin, std::size_t end, std::vector<double>& box_slack) {
    constexpr int kMaxSampled = 256;
    const bool large = out.triangles_.size() > kSearchedMesh;
    const int corners_up_to = large ? 1 : 4;
    const int sampled_up_to = large || !options.sampled_slack ? 0 : kMaxSampled;
    for (std::size_t i = end; i-- > begin;) {
      BvhNode<BV>& node = out.nodes_[i];
      const EnclosingBox box = enclosing_box(node.volume);
      double bound = 2.0 * box.half.norm() * (1 + kPoseMargin);  // the node's triangles lie in the box
      if (node.count <= sampled_up_to) {  // the tightest; where it is taken the others add little
        bound = std::min(bound, sampled_slack(box, node));
      } else {
        if (!node.is_leaf()) bound = std::min(bound, composed_slack(box, node, box_slack));
        if (node.count <= corners_up_to) bound = std::min(bound, corner_slack(box, node, large));
      }
      box_slack[i] = bound;
      node.size = radius(node.volume);
      node.slack = std::min(2.0 * node.size, bound);
    }
  }

  void compute_slack() {
    evaluations = 0;
    std::vector<double> box_slack(out.nodes_.size());
    const std::size_t right = out.nodes_.empty() || out.nodes_[0].is_leaf() ? 0 : out.nodes_[0].right;
    if (out.nodes_.size() > 2 * kParallelBuild && right > 0) {  // the root's two subtrees at once
      run_beside([&] { compute_slack(right, out.nodes_.size(), box_slack); }, [&] { compute_slack(1, right, box_slack); });
      compute_slack(0, 1, box_slack);
    } else {
      compute_slack(0, out.nodes_.size(), box_slack);
    }
    out.slack_evaluations_ = evaluations;
  }

  // Runs `aside` on a thread of its own while this thread runs `here`. Only for the root's two
  // subtrees of a mesh over kParallelBuild triangles: Bvh::build is called from the shared
  // pool's jobs (RobotCollisionModel builds every mesh and hull as one job set), where a nested
  // pool job would run serially, and one such mesh otherwise sets how long a robot takes to load.
  template <class Aside, class Here>
  static void run_beside(Aside&& aside, Here&& here) {
    std::exception_ptr failed;
    std::thread helper([&] {
      try {
        aside();
      } catch (...) {
        failed = std::current_exception();
      }
    });
    try {
      here();
    } catch (...) {
      helper.join();
      throw;
    }
    helper.join();
    if (failed) std::rethrow_exception(failed);
  }

  // The root split, then its right subtree by a second builder (same triangles and order, its
  // own node list and scratch) beside the left one; the right list is appended with its child
  // indices shifted, which keeps the nodes in pre-order.
  void top_down_in_two() {
    const int n = static_cast<int>(order.size());
    const std::int32_t root = new_node(0, n);
    out.nodes_[root].volume = fit(0, n);
    if (n <= options.max_leaf_triangles || options.max_depth <= 0) return;
    const int mid = options.method == BuildMethod::kSah ? split_by_sah(order, 0, n, prims) : split_at_centre(order, 0, n, prims);
    BvhBuilder right_half(*this, SharedInput{});
    std::int32_t left = -1;
    run_beside([&] { right_half.top_down(mid, n, 1); }, [&] { left = top_down(0, mid, 1); });
    const auto offset = static_cast<std::int32_t>(out.nodes_.size());
    for (BvhNode<BV> node : right_half.out.nodes_) {
      if (!node.is_leaf()) {
        node.left += offset;
        node.right += offset;
      }
      out.nodes_.push_back(node);
    }
    out.nodes_[root].left = left;
    out.nodes_[root].right = offset;
  }

  void find_surface_facts() {
    out.closed_ = is_closed(mesh);
    for (std::int32_t v : component_representatives(mesh)) out.component_points_.push_back(mesh.vertices[v]);
  }

  void build_tree() {
    if (options.method == BuildMethod::kBottomUp) {
      const std::vector<Cluster> tree = agglomerate();
      order.clear();
      emit(tree, static_cast<std::int32_t>(tree.size() - 1));
    } else {
      order.resize(prims.size());
      std::iota(order.begin(), order.end(), 0);
      out.nodes_.reserve(2 * prims.size());
      if (prims.size() > kParallelBuild) {
        top_down_in_two();
      } else {
        top_down(0, static_cast<int>(order.size()), 0);
      }
    }
    out.triangles_.reserve(order.size());
    out.planes_.reserve(order.size());
    out.spheres_.reserve(order.size());
    for (std::int32_t t : order) {
      const Triangle tri = mesh.triangle(t);
      out.triangles_.push_back(tri);
      out.planes_.push_back(TrianglePlane::of(tri[0], tri[1], tri[2]));
      out.spheres_.push_back(TriangleSphere::of(tri));
    }
    out.triangle_ids_ = order;
    compute_slack();
  }

  Bvh<BV> run() {
    if (mesh.triangles.empty()) {
      find_surface_facts();
      return std::move(out);
    }
    if (prims.size() > kParallelBuild) {  // closedness and components do not need the tree
      run_beside([&] { find_surface_facts(); }, [&] { build_tree(); });
    } else {
      find_surface_facts();
      build_tree();
    }
    return std::move(out);
  }
};

template <class BV>
Bvh<BV> Bvh<BV>::build(const TriangleMesh& mesh, const BuildOptions& options) {
  return BvhBuilder<BV>(mesh, options).run();
}

template <class BV>
std::size_t Bvh<BV>::memory_bytes() const {
  return nodes_.size() * sizeof(BvhNode<BV>) + triangles_.size() * sizeof(Triangle) +
         planes_.size() * sizeof(TrianglePlane) + spheres_.size() * sizeof(TriangleSphere) +
         triangle_ids_.size() * sizeof(std::int32_t) + component_points_.size() * sizeof(Vec3);
}

namespace {

// A BVH's nodes with their depth (the root's is 1), as geometry/tree_walk.h walks them.
template <class BV>
struct DepthView {
  struct Node {
    std::int32_t index;
    int depth;
  };
  const std::vector<BvhNode<BV>>& nodes;
  bool is_leaf(const Node& n) const { return nodes[n.index].is_leaf(); }
  template <class F>
  void children(const Node& n, F&& f) const {
    f(Node{nodes[n.index].left, n.depth + 1});
    f(Node{nodes[n.index].right, n.depth + 1});
  }
};

}  // namespace

template <class BV>
int Bvh<BV>::depth() const {
  if (nodes_.empty()) return 0;
  int deepest = 0;
  using Node = typename DepthView<BV>::Node;
  depth_first_walk(
      DepthView<BV>{nodes_}, Node{0, 1},
      [&](const Node& n) {
        deepest = std::max(deepest, n.depth);
        return Visit::kEnter;
      },
      [](const Node&) { return false; });
  return deepest;
}

template class Bvh<Aabb>;
template class Bvh<Obb>;
template class Bvh<Sphere>;
template class Bvh<Kdop14>;
template class Bvh<Kdop18>;
template class Bvh<Kdop26>;
template class Bvh<Rss>;

}  // namespace bvh_collision
