// The proxy build's two searches, so that it grows as n log n of what it builds instead of n^2
// (link_proxy.cpp): which chosen sphere holds a point (the cover's proof asks it for every
// surface piece and every cube), and which sample points a candidate sphere covers (the greedy
// seed). Private to the narrowphase's proxy build.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

// Spheres by position, for "is p inside some sphere (by a margin)?": a hashed grid per scale. A
// sphere lives at the finest scale whose cell is more than twice its radius, in the cell of its
// centre; a sphere holding p then has its centre in one of the 2 x 2 x 2 cells around p at its
// scale. A query costs 8 look-ups per scale in use (a link's spheres span a few scales), not a
// walk over every sphere; spheres may be added between queries. The cells are an open-addressed
// table, and each sphere's centre and radius sit in its cell's list: a query reads no other array.
class SphereGrid {
 public:
  struct Entry {
    Vec3 centre;
    double radius;
    std::uint32_t id;
    std::uint32_t next;  // the entry before it in its cell, or kNone
  };

  explicit SphereGrid(double finest_cell)
      : finest_(finest_cell), inverse_(1.0 / finest_cell), keys_(kInitialSlots, kEmpty), heads_(kInitialSlots) {
    double cell = finest_, inverse = inverse_;  // (each scale's: products by powers of two, exact)
    for (int scale = 0; scale < kScales; ++scale, cell *= 2.0, inverse *= 0.5) cells_[scale] = cell, inverses_[scale] = inverse;
  }

  void insert(std::uint32_t id, const Vec3& centre, double radius) {
    int scale = 0;
    double cell = finest_, inverse = inverse_;
    while (radius > kFill * cell && scale < kScales - 1) cell *= 2.0, inverse *= 0.5, ++scale;
    used_ |= 1u << scale;
    if (2 * (count_ + 1) > keys_.size()) grow();
    const std::uint64_t key =
        key_of(scale, cell_of(centre.x(), inverse), cell_of(centre.y(), inverse), cell_of(centre.z(), inverse));
    std::size_t slot = slot_of(key);
    if (keys_[slot] == kEmpty) keys_[slot] = key, heads_[slot] = kNone, ++count_;
    occupied_[filter_bit(key) >> 6] |= 1ull << (filter_bit(key) & 63);
    entries_.push_back({centre, radius, id, heads_[slot]});
    heads_[slot] = static_cast<std::uint32_t>(entries_.size() - 1);
  }

  // Calls visit(entry) for every sphere of radius >= min_radius that may hold p (a superset of
  // them) until it returns true; whether one did.
  template <class Visit>
  bool any_near(const Vec3& p, double min_radius, Visit&& visit) const {
    for (std::uint32_t used = used_; used != 0; used &= used - 1) {  // (the scales in use only)
      const int scale = __builtin_ctz(used);
      const double cell = cells_[scale], inverse = inverses_[scale];
      if (kFill * cell < min_radius && scale < kScales - 1) continue;  // every sphere here is smaller
      // The lower corner cell of the 2 x 2 x 2 around p: a centre within kFill cells of p lies in
      // one of them, rounding aside (room of 0.01 cell).
      const std::int64_t x = cell_of(p.x() * inverse - 0.5), y = cell_of(p.y() * inverse - 0.5),
                         z = cell_of(p.z() * inverse - 0.5);
      for (int k = 0; k < 8; ++k) {
        const std::uint64_t key = key_of(scale, x + (k & 1), y + ((k >> 1) & 1), z + ((k >> 2) & 1));
        if (!(occupied_[filter_bit(key) >> 6] & (1ull << (filter_bit(key) & 63)))) continue;  // an empty cell, mostly
        const std::size_t slot = slot_of(key);
        if (keys_[slot] == kEmpty) continue;
        for (std::uint32_t e = heads_[slot]; e != kNone; e = entries_[e].next) {
          if (visit(entries_[e])) return true;
        }
      }
    }
    return false;
  }

 private:
  static constexpr int kScales = 30;            // 2^30 times the finest cell: beyond any link
  static constexpr double kFill = 0.49;         // radius / cell: the half a cell, with room for rounding
  static constexpr std::uint32_t kNone = ~0u;
  static constexpr std::uint64_t kEmpty = ~0ull;  // no key has all its bits set (the scale has 5)
  static constexpr std::size_t kInitialSlots = 64;
  // (By the cell's inverse, a power of two times the finest's: a product, not a division.)
  static std::int64_t cell_of(double x, double inverse) { return cell_of(x * inverse); }
  static std::int64_t cell_of(double scaled) { return static_cast<std::int64_t>(std::floor(scaled)); }
  // 5 bits of scale and 19 of each coordinate (wrapped: a collision only adds candidates).
  static std::uint64_t key_of(int scale, std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::uint64_t kMask = (1u << 19) - 1;
    return (static_cast<std::uint64_t>(scale) << 57) | ((static_cast<std::uint64_t>(x) & kMask) << 38) |
           ((static_cast<std::uint64_t>(y) & kMask) << 19) | (static_cast<std::uint64_t>(z) & kMask);
  }
  // A bit per hashed key, set for every cell in use: most of a query's cells are empty (95 % on
  // panda's build), and the filter's 32 KB answers those without a probe of the table.
  static constexpr int kFilterBits = 18;
  static std::size_t filter_bit(std::uint64_t key) {
    return static_cast<std::size_t>((key * 0xC2B2AE3D27D4EB4Full) >> (64 - kFilterBits));
  }
  // The key's slot, or the empty one where it would go (linear probing; the table is at most half full).
  std::size_t slot_of(std::uint64_t key) const {
    const std::size_t mask = keys_.size() - 1;
    std::size_t slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 32) & mask;
    while (keys_[slot] != kEmpty && keys_[slot] != key) slot = (slot + 1) & mask;
    return slot;
  }
  void grow() {
    std::vector<std::uint64_t> keys(keys_.size() * 2, kEmpty);
    std::vector<std::uint32_t> heads(keys.size());
    keys.swap(keys_), heads.swap(heads_);
    for (std::size_t i = 0; i < keys.size(); ++i) {
      if (keys[i] == kEmpty) continue;
      const std::size_t slot = slot_of(keys[i]);
      keys_[slot] = keys[i], heads_[slot] = heads[i];
    }
  }

  double finest_, inverse_;
  std::array<double, kScales> cells_{}, inverses_{};  // per scale: its cell and the cell's inverse
  std::uint32_t used_ = 0;
  std::size_t count_ = 0;              // cells in use
  std::vector<std::uint64_t> occupied_ = std::vector<std::uint64_t>(std::size_t{1} << (kFilterBits - 6), 0);  // the filter's bits
  std::vector<std::uint64_t> keys_;    // cell key per slot
  std::vector<std::uint32_t> heads_;   // slot -> its cell's latest entry
  std::vector<Entry> entries_;         // in insertion order
};

// Points for ball queries: a k-d tree (median splits on the widest axis, boxes per node), built
// once in n log n; a ball query costs the depth plus what it finds.
class PointTree {
 public:
  explicit PointTree(const std::vector<Vec3>& points) : points_(points), order_(points.size()) {
    std::iota(order_.begin(), order_.end(), 0u);
    if (!points_.empty()) build(0, static_cast<std::uint32_t>(order_.size()));
    for (int k = 0; k < 3; ++k) {
      sorted_[k].reserve(order_.size());
      for (const std::uint32_t i : order_) sorted_[k].push_back(points_[i][k]);
    }
  }

  // Calls found(index) for every point within `radius` of `centre` (inclusive), in the tree's
  // order (not the points').
  template <class Found>
  void in_ball(const Vec3& centre, double radius, Found&& found) const {
    if (nodes_.empty() || !(radius >= 0.0)) return;
    const double r2 = radius * radius;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if ((centre - centre.cwiseMax(n.lo).cwiseMin(n.hi)).squaredNorm() > r2) continue;
      const Vec3 far = (n.lo - centre).cwiseAbs().cwiseMax((n.hi - centre).cwiseAbs());
      if (far.squaredNorm() <= r2) {  // the node's box is in the ball: all of its points are
        for (std::uint32_t i = n.begin; i < n.end; ++i) found(order_[i]);
        continue;
      }
      if (n.right == 0) {
        // Which of the leaf's points are in, first (a loop of arithmetic only, the squared norm
        // summed as Vec3::squaredNorm sums it), then the calls.
        const double* xs = sorted_[0].data() + n.begin;
        const double* ys = sorted_[1].data() + n.begin;
        const double* zs = sorted_[2].data() + n.begin;
        const std::uint32_t count = n.end - n.begin;
        std::uint32_t in = 0;
        for (std::uint32_t i = 0; i < count; ++i) {
          const double dx = xs[i] - centre.x(), dy = ys[i] - centre.y(), dz = zs[i] - centre.z();
          in |= static_cast<std::uint32_t>((dx * dx + dy * dy) + dz * dz <= r2) << i;
        }
        for (; in != 0; in &= in - 1) found(order_[n.begin + static_cast<std::uint32_t>(__builtin_ctz(in))]);
        continue;
      }
      stack[top++] = n.right;
      stack[top++] = n.left;
    }
  }

 private:
  struct Node {
    Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();
    std::uint32_t begin = 0, end = 0;
    std::uint32_t left = 0, right = 0;  // right == 0: a leaf
  };
  static constexpr std::uint32_t kLeafSize = 32;  // (found 16-64 alike on panda's build; 8 took 4 % more)
  static_assert(kLeafSize <= 32, "in_ball marks a leaf's points in 32 bits");

  std::uint32_t build(std::uint32_t begin, std::uint32_t end) {
    const std::uint32_t index = static_cast<std::uint32_t>(nodes_.size());
    nodes_.emplace_back();
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (std::uint32_t i = begin; i < end; ++i) lo = lo.cwiseMin(points_[order_[i]]), hi = hi.cwiseMax(points_[order_[i]]);
    Node n{lo, hi, begin, end, 0, 0};
    if (end - begin > kLeafSize) {
      int axis = 0;
      (hi - lo).maxCoeff(&axis);
      const std::uint32_t mid = begin + (end - begin) / 2;
      std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                       [&](std::uint32_t a, std::uint32_t b) { return points_[a][axis] < points_[b][axis]; });
      n.left = build(begin, mid);
      n.right = build(mid, end);
    }
    nodes_[index] = n;
    return index;
  }

  const std::vector<Vec3>& points_;
  std::vector<std::uint32_t> order_;
  std::array<std::vector<double>, 3> sorted_;  // points_' coordinates in order_'s order: a leaf's lie together
  std::vector<Node> nodes_;
};

}  // namespace bvh_collision
