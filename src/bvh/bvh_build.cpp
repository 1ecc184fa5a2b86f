#include "bvh_collision/bvh/bvh.h"

#include <algorithm>
#include <numeric>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/distance.h"

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

// The seed's split: the plane through the centre of the longest axis of the node's box,
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
  const TriangleMesh& mesh;
  BuildOptions options;
  std::vector<Prim> prims;
  Order order;
  std::vector<Vec3> scratch;
  Bvh<BV> out;

  BvhBuilder(const TriangleMesh& m, const BuildOptions& o) : mesh(m), options(o) {
    prims.resize(mesh.triangles.size());
    for (std::size_t i = 0; i < prims.size(); ++i) {
      const Triangle t = mesh.triangle(i);
      for (int k = 0; k < 3; ++k) prims[i].box.extend(t[k]);
      prims[i].centroid = (t[0] + t[1] + t[2]) / 3.0;
    }
  }

  // The volume fitted to the points of triangles order[begin, end).
  BV fit(int begin, int end) {
    scratch.clear();
    for (int i = begin; i < end; ++i) {
      const Triangle t = mesh.triangle(order[i]);
      scratch.insert(scratch.end(), {t[0], t[1], t[2]});
    }
    return fit_volume<BV>(scratch.data(), scratch.size());
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
  // their children's (the seed's bottom-up update); leaves are fitted.
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

  // Slack: the largest distance from a point of the volume to the node's triangles, bounded by
  // sampling the centres of 4x4x4 cells of an enclosing box (distance is 1-Lipschitz, so adding
  // the cell's half diagonal makes it an upper bound). Large nodes use the diameter.
  void compute_slack() {
    constexpr int kCells = 4;
    constexpr int kMaxSampled = 256;
    for (auto& node : out.nodes_) {
      node.size = radius(node.volume);
      node.slack = 2.0 * node.size;
      if (node.count > kMaxSampled) continue;
      const EnclosingBox box = enclosing_box(node.volume);
      double worst = 0.0;
      for (int i = 0; i < kCells * kCells * kCells; ++i) {
        const Vec3 u((i % kCells + 0.5) / kCells, (i / kCells % kCells + 0.5) / kCells, (i / (kCells * kCells) + 0.5) / kCells);
        const Vec3 s = box.center + box.axes * (box.half.cwiseProduct(2.0 * u - Vec3::Ones()));
        double best = std::numeric_limits<double>::infinity();
        for (int t = node.first; t < node.first + node.count && best > worst; ++t) {
          const Triangle& tri = out.triangles_[t];
          best = std::min(best, (closest_point_on_triangle(s, tri[0], tri[1], tri[2]) - s).norm());
        }
        worst = std::max(worst, best);
      }
      node.slack = std::min(node.slack, (worst + box.half.norm() / kCells) * (1 + kPoseMargin));
    }
  }

  Bvh<BV> run() {
    out.closed_ = is_closed(mesh);
    for (std::int32_t v : component_representatives(mesh)) out.component_points_.push_back(mesh.vertices[v]);
    if (mesh.triangles.empty()) return std::move(out);
    if (options.method == BuildMethod::kBottomUp) {
      const std::vector<Cluster> tree = agglomerate();
      order.clear();
      emit(tree, static_cast<std::int32_t>(tree.size() - 1));
    } else {
      order.resize(prims.size());
      std::iota(order.begin(), order.end(), 0);
      top_down(0, static_cast<int>(order.size()), 0);
    }
    out.triangles_.reserve(order.size());
    for (std::int32_t t : order) {
      const Triangle tri = mesh.triangle(t);
      out.triangles_.push_back(tri);
      out.planes_.push_back(TrianglePlane::of(tri[0], tri[1], tri[2]));
      out.spheres_.push_back(TriangleSphere::of(tri));
    }
    out.triangle_ids_ = order;
    compute_slack();
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

template <class BV>
int Bvh<BV>::depth() const {
  if (nodes_.empty()) return 0;
  std::vector<std::pair<std::int32_t, int>> stack{{0, 1}};
  int deepest = 0;
  while (!stack.empty()) {
    const auto [n, d] = stack.back();
    stack.pop_back();
    deepest = std::max(deepest, d);
    if (!nodes_[n].is_leaf()) {
      stack.push_back({nodes_[n].left, d + 1});
      stack.push_back({nodes_[n].right, d + 1});
    }
  }
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
