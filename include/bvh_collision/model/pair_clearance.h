// Proven clearance of the self pairs that few joints move: per checked pair whose relative pose
// depends on one or two state variables (a wrist link and the hand, two fingers, links two joints
// apart), or on three when a fine grid fits the budget (panda's forearm and a finger: two wrist
// joints and the finger's short travel), a grid over those variables holding, per cell, a lower bound on the pair's exact
// distance anywhere in the cell. Such pairs sit close in every state, so a sphere tree or an OBB
// hierarchy has to descend far to tell them apart each time (a few such pairs took most of the
// sphere tests of a proxy self check: docs/performance.md); the table
// settles them with one lookup whenever the bound clears the padding.
//
// Why the bound holds: the exact distance d(c) between the two links at the cell's centre c
// (solids, no tolerance) is computed at build time. Moving the state from c to any q of the cell
// moves each point of link L by at most sum_v rate(L, v) |q_v - c_v| (RobotCollisionModel's
// motion rates, valid within the joint limits the grid spans), so the distance, 1-Lipschitz in
// the points, is at least d(c) - sum_v (rate(a, v) + rate(b, v)) h_v with h_v the cell's half
// width. Only the variables on the pair's kinematic path change their relative pose; the others
// move both links as one. States outside the grid (a value beyond the limits) get no bound.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <vector>

namespace bvh_collision {

class RobotCollisionModel;

struct PairClearanceGrid {
  static constexpr int kMaxDims = 3;
  std::size_t pair = 0;             // index into RobotCollisionModel::checked_pairs()
  int dims = 0;                     // 1 to kMaxDims variables
  std::array<int, kMaxDims> variable{-1, -1, -1};
  std::array<double, kMaxDims> lower{}, cell{};  // the grid's first value and cell width per variable
  std::array<int, kMaxDims> cells{1, 1, 1};
  std::array<bool, kMaxDims> periodic{};  // a continuous joint: values wrap by 2 pi
  std::vector<float> bound;         // per cell (first variable fastest): lower bound on the distance (m)
  // Coarser grids for segments, coarsest last: pyramid[L - 1]'s cell covers 2^L cells of `bound`
  // per variable (fewer at the far edges) and holds the least bound among them, down to one cell.
  std::vector<std::vector<float>> pyramid;
  int cells_at(int level, int k) const { return ((cells[k] - 1) >> level) + 1; }
};

class PairClearance {
 public:
  PairClearance() = default;
  // Grids for every checked pair of `model` that one or two variables move (three when, with four
  // times the budget, half a cell closes the pair by at most 1 cm per variable), each with at
  // most about `max_cells` cells (finer where the links move faster per unit of the variable). A
  // grid of one or two variables that leaves some cells without a bound, at most a quarter, is
  // built again with kRefinedCells times the budget when the finer cells would settle most of
  // those and take at most the coarse grid's tests plus 8,192: a pair that comes within a
  // centimetre or two somewhere without touching (ur5e's forearm and wrist_2_link, 8 mm at the
  // closest) is then settled everywhere, and the pairs that never come that close keep their
  // small grids.
  static constexpr std::size_t kRefinedCells = 16;
  static PairClearance build(const RobotCollisionModel& model, std::size_t max_cells = 4096);

  // A lower bound on the distance of checked pair `pair` in `state`; -infinity when the pair has
  // no grid or a value lies outside it.
  double lower_bound(std::size_t pair, const double* state) const {
    const int g = grid_of_.empty() ? -1 : grid_of_[pair];
    return g < 0 ? -std::numeric_limits<double>::infinity() : grid_bound(grids_[g], state);
  }
  // Is checked pair `pair` farther apart than `clearance` at every state of the straight segment
  // from `a` to `b`? True when every cell the segment's values of the grid's variables cross has
  // a larger bound: nine cells along it looked up first (most segments that cross an unbounded
  // cell meet it at one of those), then proven from the coarsest grid of the pyramid down, the
  // segment cut in halves wherever a coarse cell does not settle it (a long motion through
  // settled cells costs a few lookups). False without a grid, for a value outside it, a periodic
  // variable, or beyond its budget of boxes looked at (then the other tests serve): `max_visits`,
  // or 8 a finest cell the segment crosses (at most 4,096) where that is more.
  bool clear_over(std::size_t pair, const double* a, const double* b, double clearance, int max_visits = 32) const;
  bool has_grid(std::size_t pair) const { return !grid_of_.empty() && grid_of_[pair] >= 0; }
  // The same grids for a model whose first checked pairs are these and which has `pairs` in all
  // (RobotCollisionModel::carrying appends a carried object's pairs): the new ones have none.
  PairClearance for_pairs(std::size_t pairs) const {
    PairClearance out = *this;
    if (!out.grid_of_.empty()) out.grid_of_.resize(pairs, -1);
    return out;
  }
  const std::vector<PairClearanceGrid>& grids() const { return grids_; }
  std::size_t memory_bytes() const;
  double build_seconds() const { return build_seconds_; }  // built or read
  bool from_cache() const { return from_cache_; }  // read from a folder (model/pair_clearance_cache.h)

 private:
  friend struct PairClearanceFile;  // model/pair_clearance_cache.cpp: stores and restores the grids as built
  static double grid_bound(const PairClearanceGrid& grid, const double* state);

  std::vector<PairClearanceGrid> grids_;
  std::vector<int> grid_of_;  // per checked pair: its grid, or -1
  double build_seconds_ = 0.0;
  bool from_cache_ = false;
};

}  // namespace bvh_collision
