// A self pair's clearance along one variable while the other variables of its kinematic path are
// held: what a planning group's motion does to a pair of links of which one is outside the group
// (pr2's right shoulder turning beside its tucked left gripper). The pair's relative pose is then
// a function of that one value, and the pair sits at the same few millimetres for the whole of
// its range: every motion of the group, bisected until its growth falls below the gap, paid one
// exact distance per few milliradians (most of pr2's torso-and-arm plan time:
// docs/planning.md). Proven once instead, lazily, per stretch of the variable's range.
//
// Why a stretch's proof holds: the links tested at the stretch's centre value c and found farther
// apart than need + rate * h (h its half-width, slightly widened for rounding), and no point of
// either link moves by more than rate * |q - c| as the value goes from c to q within the joint's
// limits (RobotCollisionModel's motion rates, summed over the two links: the pair's rate), so the
// pair stays farther apart than `need` over the whole stretch. A stretch that is not proven is
// halved, down to stretches that close the pair by at most kLeafClosing. (Private to src/query.)
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <vector>

namespace bvh_collision {

class RobotCollisionModel;

namespace held_pair {

// The finest stretch closes the pair by at most this much: a pair held closer than it over some
// value is left to the motion's own intervals there.
constexpr double kLeafClosing = 2.5e-4;
constexpr int kMaxDepth = 16;  // 2^17 bytes at most per pair

// Proven stretches of one variable's range [lower, upper]: a binary tree of halvings, each node
// untested, clear or near.
class StretchTree {
 public:
  // Forgets every stretch; `rate`: how fast the variable closes the pair (m per unit of it).
  void reset(double lower, double upper, double rate) {
    lower_ = lower;
    width_ = upper - lower;
    rate_ = rate;
    depth_ = 0;
    while (depth_ < kMaxDepth && std::ldexp(rate * width_, -depth_ - 1) > kLeafClosing) ++depth_;
    node_.assign((std::size_t{2} << depth_) - 1, 0);
  }

  // Does every value of [lo, hi] lie in a stretch proven clear? `near(c, h)`: are the links within
  // need + rate * h of each other at value c (the caller's exact test)? Called for untested
  // stretches only, at most `budget` times a query (then not proven; what was tested stays).
  template <class Near>
  bool clear(double lo, double hi, int budget, Near&& near) {
    if (!(lo >= lower_ && hi <= lower_ + width_) || node_.empty()) return false;
    struct Item {
      int depth;
      std::size_t index;  // within its depth
    };
    std::array<Item, 2 * (kMaxDepth + 1)> stack;  // depth first: at most two a level wait
    int top = 0;
    stack[top++] = {0, 0};
    while (top > 0) {
      const Item item = stack[--top];
      const double w = std::ldexp(width_, -item.depth);
      const double a = lower_ + static_cast<double>(item.index) * w;
      // Widened by rounding's worth: a value on the edge of two stretches is in both.
      const double slack = 1e-12 * (1.0 + std::abs(a) + w);
      if (a + w + slack < lo || a - slack > hi) continue;
      signed char& node = node_[(std::size_t{1} << item.depth) - 1 + item.index];
      if (node == 0) {
        if (budget-- <= 0) return false;
        node = near(a + 0.5 * w, 0.5 * w + slack) ? -1 : 1;
      }
      if (node > 0) continue;
      if (item.depth == depth_) return false;
      stack[top++] = {item.depth + 1, 2 * item.index + 1};
      stack[top++] = {item.depth + 1, 2 * item.index};
    }
    return true;
  }

 private:
  double lower_ = 0.0, width_ = 0.0, rate_ = 0.0;
  int depth_ = 0;
  std::vector<signed char> node_;  // per node (depth d, index i at 2^d - 1 + i): 0 untested, 1 clear, -1 near
};

// A pair's tree with what it was proven for: the moving variable and the values the path's other
// variables were held at.
struct HeldPair {
  int variable = -1;
  std::vector<double> held;  // per path variable (the pair's rate weights' order); the moving one's is 0
  StretchTree tree;
};

// A thread's trees for one robot model (and clearance), per checked pair: proven once for every
// scene checker of that model (a planner's problems each get a checker of their own). `model`
// tells when the model changed, even where a destroyed one stood.
struct HeldPairs {
  std::weak_ptr<const RobotCollisionModel> model;
  double need_extra = -1.0;  // the clearance asked beyond the paddings
  std::vector<HeldPair> pairs;
};

}  // namespace held_pair
}  // namespace bvh_collision
