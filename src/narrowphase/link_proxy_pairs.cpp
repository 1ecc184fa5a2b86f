// Pairs of link proxies: do two sphere trees come within a padding, and how far apart are they
// (narrowphase/link_proxy.h), by the pair walk of geometry/tree_walk.h.
#include "bvh_collision/narrowphase/link_proxy.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/tree_walk.h"

namespace bvh_collision {
namespace {

// r * p + t written out: at -O2 GCC leaves Eigen's 3x3 product as a call, and this runs once per
// sphere pair visited.
inline Vec3 apply(const Mat3& r, const Vec3& t, const Vec3& p) {
  return Vec3(r(0, 0) * p[0] + r(0, 1) * p[1] + r(0, 2) * p[2] + t[0], r(1, 0) * p[0] + r(1, 1) * p[1] + r(1, 2) * p[2] + t[1],
              r(2, 0) * p[0] + r(2, 1) * p[1] + r(2, 2) * p[2] + t[2]);
}

// b's sphere centres in a's frame (one transform per sphere of b visited), and the margin that
// covers the rounding of a pair walk.
struct PairFrame {
  Mat3 r;
  Vec3 t;
  double margin;
};

PairFrame pair_frame(const LinkProxy& a, const Transform& pose_a, const LinkProxy& b, const Transform& pose_b) {
  const Transform b_in_a = relative_transform(pose_a, pose_b);
  const ProxySphere& ra = a.spheres().front();
  const ProxySphere& rb = b.spheres().front();
  return {b_in_a.R, b_in_a.t,
          pose_margin(pose_a.t.norm() + pose_b.t.norm() + ra.center.norm() + ra.radius + rb.center.norm() + rb.radius)};
}

// A proxy's sphere tree as geometry/tree_walk.h walks it: spheres by index in depth-first
// order, a sphere's subtree ending at its `skip`.
struct SphereTreeView {
  using Node = std::int32_t;
  const ProxySphere* s;
  bool is_leaf(Node i) const { return s[i].skip == i + 1; }
  template <class F>
  void children(Node i, F&& f) const {
    for (std::int32_t k = i + 1; k < s[i].skip; k = s[k].skip) f(k);
  }
};

// A pair walk opens a's sphere unless it is a leaf or b's (not a leaf) is larger.
template <class Push>
void open_larger(const SphereTreeView& a, std::int32_t i, const SphereTreeView& b, std::int32_t j, Push&& push) {
  if (!a.is_leaf(i) && (b.is_leaf(j) || a.s[i].radius >= b.s[j].radius)) {
    a.children(i, [&](std::int32_t k) { push(k, j); });
  } else {
    b.children(j, [&](std::int32_t k) { push(i, k); });
  }
}

}  // namespace

// The pair walk with each pair tested before it is pushed, not after it is popped: when a's
// sphere is opened, b's centre is carried into a's frame once for all its children, and the
// pairs that are apart never reach the stack (the same tests, the same bits, as a walk by
// depth_first_pair_walk; pr2's arm past its tucked arm walks hundreds of sphere pairs a test).
// A witness's leaf pair meeting answers true as the walk would on reaching it: its ancestors
// contain it, so they meet too (up to rounding, which the walk's margin covers).
bool proxies_overlap(const LinkProxy& a, const Transform& pose_a, const LinkProxy& b, const Transform& pose_b,
                     double padding, ProxyWitness* witness) {
  if (a.empty() || b.empty()) return false;
  const ProxySphere* sa = a.spheres().data();
  const ProxySphere* sb = b.spheres().data();
  const PairFrame frame = pair_frame(a, pose_a, b, pose_b);
  const Mat3 r = frame.r;
  const Vec3 t = frame.t;
  const double slack = padding + frame.margin;
  // (Not "apart" is not "meets": a NaN stays in.)
  auto meets = [sa, slack](std::int32_t i, const Vec3& cb, double rb) {
    const double reach = sa[i].radius + rb + slack;
    return !((sa[i].center - cb).squaredNorm() > reach * reach);
  };
  auto leaf = [](const ProxySphere* s, std::int32_t i) { return s[i].skip == i + 1; };
  auto found = [witness](std::int32_t i, std::int32_t j) {
    if (witness != nullptr) *witness = {i, j};
    return true;
  };
  if (witness != nullptr && witness->a >= 0 && witness->b >= 0 && witness->a < static_cast<std::int32_t>(a.spheres().size()) &&
      witness->b < static_cast<std::int32_t>(b.spheres().size()) && leaf(sa, witness->a) && leaf(sb, witness->b) &&
      meets(witness->a, apply(r, t, sb[witness->b].center), sb[witness->b].radius)) {
    return true;
  }
  if (!meets(0, apply(r, t, sb[0].center), sb[0].radius)) return false;
  if (leaf(sa, 0) && leaf(sb, 0)) return found(0, 0);
  TraversalStack<NodePair<std::int32_t, std::int32_t>> stack;
  stack.push({0, 0});
  while (!stack.empty()) {
    const auto [i, j] = stack.pop();
    // Open a's sphere unless it is a leaf or b's (not a leaf) is larger (open_larger's rule).
    if (!leaf(sa, i) && (leaf(sb, j) || sa[i].radius >= sb[j].radius)) {
      const Vec3 cb = apply(r, t, sb[j].center);
      const bool b_leaf = leaf(sb, j);
      for (std::int32_t k = i + 1; k < sa[i].skip; k = sa[k].skip) {
        if (!meets(k, cb, sb[j].radius)) continue;
        if (b_leaf && leaf(sa, k)) return found(k, j);
        stack.push({k, j});
      }
    } else {
      const bool a_leaf = leaf(sa, i);
      for (std::int32_t k = j + 1; k < sb[j].skip; k = sb[k].skip) {
        if (!meets(i, apply(r, t, sb[k].center), sb[k].radius)) continue;
        if (a_leaf && leaf(sb, k)) return found(i, k);
        stack.push({i, k});
      }
    }
  }
  return false;
}

double proxies_distance(const LinkProxy& a, const Transform& pose_a, const LinkProxy& b, const Transform& pose_b,
                        double best, const ProxySlack& slack) {
  if (a.empty() || b.empty()) return best;
  const ProxySphere* sa = a.spheres().data();
  const ProxySphere* sb = b.spheres().data();
  const PairFrame frame = pair_frame(a, pose_a, b, pose_b);
  const Mat3 r = frame.r;
  const Vec3 t = frame.t;
  const double margin = frame.margin;
  // The smallest gap of a pair of spheres left unopened because it was within the slack of best.
  double unopened = best;
  depth_first_pair_walk(
      SphereTreeView{sa}, SphereTreeView{sb}, 0, 0,
      [sa, sb, r, t, margin, &best, &unopened, &slack](std::int32_t i, std::int32_t j) {
        // Spheres contain their subtrees: this gap bounds every leaf pair below from below.
        const double gap = std::max(0.0, (sa[i].center - apply(r, t, sb[j].center)).norm() - sa[i].radius - sb[j].radius - margin);
        if (gap >= best) return Visit::kSkip;
        if (sa[i].skip == i + 1 && sb[j].skip == j + 1) {
          best = gap;
          return Visit::kSkip;
        }
        if (slack.leaves(gap, best)) {
          unopened = std::min(unopened, gap);
          return Visit::kSkip;
        }
        return Visit::kEnter;
      },
      [](std::int32_t, std::int32_t) { return false; },  // leaf pairs are settled in visit (their gap)
      [sa, sb](std::int32_t i, std::int32_t j, auto&& push) { open_larger(SphereTreeView{sa}, i, SphereTreeView{sb}, j, push); });
  return std::min(best, unopened);
}

}  // namespace bvh_collision
