#include "bvh_collision/model/pair_clearance.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/model/detail/pair_clearance_shape.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/narrowphase/shape_pairs.h"

namespace bvh_collision {
namespace {

constexpr double kTwoPi = 6.283185307179586;
// Taken off every stored bound: the rounding of the distance routine, the kinematics and the
// cell lookup (a value on a cell's edge may land in the neighbouring cell) stay far below it.
constexpr double kBoundMargin = 1e-6;

// The state variables that move link b relative to link a: those of the joints on one chain and
// not the other. False when a joint there is not a variable (floating, planar).
bool path_variables(const RobotModel& robot, int a, int b, std::vector<int>& out) {
  const auto& joints = robot.joints();
  auto chain = [&](int link) {
    std::vector<int> c;
    for (int j = robot.links()[link].parent_joint; j >= 0; j = robot.links()[joints[j].parent_link].parent_joint) c.push_back(j);
    return c;
  };
  const std::vector<int> ca = chain(a), cb = chain(b);
  out.clear();
  for (const auto* side : {&ca, &cb}) {
    const auto& other = side == &ca ? cb : ca;
    for (const int j : *side) {
      if (std::find(other.begin(), other.end(), j) != other.end()) continue;
      const RobotJoint& joint = joints[j];
      if (joint.type == JointType::kFixed) continue;
      const int v = joint.mimic >= 0 ? joints[joint.mimic].variable : joint.variable;
      if (v < 0) return false;
      if (std::find(out.begin(), out.end(), v) == out.end()) out.push_back(v);
    }
  }
  return true;
}

// The joint whose value is variable v (not a mimic).
const RobotJoint* variable_joint(const RobotModel& robot, int v) {
  for (const RobotJoint& j : robot.joints()) {
    if (j.variable == v && j.mimic < 0) return &j;
  }
  return nullptr;
}

// Rounds x down to a float.
float float_below(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

// Do links a and b (solids) come within `padding` of each other? Exact, no tolerance.
bool links_within(const RobotCollisionModel& model, int a, int b, const std::vector<Transform>& poses, double padding) {
  PairRequest request;
  request.padding = padding;
  QueryStats stats;
  return compounds_collide(model.compound(a), poses[a], model.compound(b), poses[b], request, nullptr, stats);
}

using Cells = std::array<int, PairClearanceGrid::kMaxDims>;

// A grid of three variables gets this many times the cell budget (a float per cell: 64 KB at the
// default) and is built only when that makes it this fine (half a cell closes the pair by at most
// this per variable): coarser, most of its cells would hold no bound, at the cost of its build.
constexpr double kThreeVariableBudget = 4.0;
constexpr double kFineClosing = 0.01;

// The grid's shape for a pair moved by `vars` (nullopt-like: dims 0 when a variable has no
// finite range, or three variables need coarser cells than kFineClosing): cells per variable in
// proportion to how far the links move over its range.
PairClearanceGrid grid_shape(const RobotCollisionModel& model, int a, int b, const std::vector<int>& vars,
                             std::size_t max_cells) {
  PairClearanceGrid g;
  std::array<double, PairClearanceGrid::kMaxDims> sweep{};  // how far the pair can close over the variable's whole range
  for (std::size_t k = 0; k < vars.size(); ++k) {
    const RobotJoint* joint = variable_joint(model.robot(), vars[k]);
    if (!joint) return {};
    if (joint->type == JointType::kContinuous) {
      g.periodic[k] = true;
      g.lower[k] = -0.5 * kTwoPi;
      g.cell[k] = kTwoPi;
    } else if (joint->bounded && std::isfinite(joint->lower) && std::isfinite(joint->upper) && joint->upper >= joint->lower) {
      g.lower[k] = joint->lower;
      g.cell[k] = std::max(joint->upper - joint->lower, 1e-12);
    } else {
      return {};
    }
    g.variable[k] = vars[k];
    sweep[k] = g.cell[k] * (model.motion_rates()[a][vars[k]] + model.motion_rates()[b][vars[k]]);
  }
  g.dims = static_cast<int>(vars.size());
  // Half a cell closes the pair by at most `closing` per variable: 1 mm, or what the budget allows.
  double product = 1.0;
  for (int k = 0; k < g.dims; ++k) product *= std::max(sweep[k], 1e-9);
  const double budget = static_cast<double>(max_cells) * (g.dims == 3 ? kThreeVariableBudget : 1.0);
  const double closing = std::max(1e-3, 0.5 * std::pow(product / budget, 1.0 / g.dims));
  if (g.dims == 3 && closing > kFineClosing) return {};
  for (int k = 0; k < g.dims; ++k) {
    const double want = std::ceil(sweep[k] / (2.0 * closing));
    g.cells[k] = static_cast<int>(std::clamp(want, 1.0, static_cast<double>(max_cells)));
    g.cell[k] /= g.cells[k];
  }
  return g;
}

std::size_t cell_index(const PairClearanceGrid& g, const Cells& i) {
  return static_cast<std::size_t>(i[0]) + static_cast<std::size_t>(g.cells[0]) * (i[1] + static_cast<std::size_t>(g.cells[1]) * i[2]);
}

// Calls f(cell index) for every cell of the block [lo, hi) (hi exclusive per variable).
template <class F>
void for_each_cell(const PairClearanceGrid& g, const Cells& lo, const Cells& hi, F&& f) {
  for (int k = lo[2]; k < hi[2]; ++k) {
    for (int j = lo[1]; j < hi[1]; ++j) {
      for (int i = lo[0]; i < hi[0]; ++i) f(cell_index(g, {i, j, k}));
    }
  }
}

// Fills the cells of a block [lo, hi) of the grid. One exact test at the block's centre, "are the
// links within settled + closing?", settles the whole block when they are not: every cell gets
// the bound `settled` (all a query needs: it only compares the bound with the padding). A block
// where they are is halved along its longest side, down to single cells, which then get no bound
// (-infinity). A boolean test stops at the first overlap or the first proof of separation:
// several times cheaper than distances on pr2's meshes.
class GridFiller {
 public:
  GridFiller(const RobotCollisionModel& model, int a, int b, PairClearanceGrid& g)
      : model_(model), a_(a), b_(b), g_(g), state_(model.robot().variable_count(), 0.0) {
    settled_ = model.paddings()[a] + model.paddings()[b] + kSettled;
    for (int k = 0; k < g.dims; ++k) rate_[k] = model.motion_rates()[a][g.variable[k]] + model.motion_rates()[b][g.variable[k]];
    g.bound.assign(static_cast<std::size_t>(g.cells[0]) * g.cells[1] * g.cells[2], 0.0f);
  }
  void fill(const Cells& lo, const Cells& hi) {
    if (++tests_ > budget_) return;  // over its budget: the caller drops the grid
    double closing = 0.0;  // from the block's centre to any point of it
    int longest = 0;
    for (int k = 0; k < g_.dims; ++k) {
      state_[g_.variable[k]] = g_.lower[k] + 0.5 * (lo[k] + hi[k]) * g_.cell[k];
      closing += 0.5 * (hi[k] - lo[k]) * g_.cell[k] * rate_[k];
      if (hi[k] - lo[k] > hi[longest] - lo[longest]) longest = k;
    }
    model_.kinematics().compute(state_.data(), poses_);
    const bool near = links_within(model_, a_, b_, poses_, settled_ + closing + kBoundMargin);
    if (near && hi[longest] - lo[longest] > 1) {
      const int mid = (lo[longest] + hi[longest]) / 2;
      Cells upper_lo = lo, lower_hi = hi;
      upper_lo[longest] = lower_hi[longest] = mid;
      fill(lo, lower_hi), fill(upper_lo, hi);
      return;
    }
    // Apart: d(centre) > settled + closing + margin, so d > settled anywhere in the block.
    const float f = near ? -std::numeric_limits<float>::infinity() : float_below(settled_);
    for_each_cell(g_, lo, hi, [&](std::size_t c) { g_.bound[c] = f; });
  }

  // Of the filled grid's cells with no bound (up to `samples` of them, spread evenly), the share
  // whose centre is apart by more than settled + `closing`: the share a grid whose cells close the
  // pair by `closing` would settle there (about: its cells are not centred on these).
  double share_apart(double closing, std::size_t samples) {
    std::vector<std::size_t> open;
    for (std::size_t c = 0; c < g_.bound.size(); ++c) {
      if (std::isinf(g_.bound[c])) open.push_back(c);
    }
    if (open.empty()) return 1.0;
    const std::size_t n = std::min(samples, open.size());
    std::size_t apart = 0;
    for (std::size_t i = 0; i < n; ++i) {
      std::size_t c = open[i * open.size() / n];
      for (int k = 0; k < g_.dims; ++k) {
        state_[g_.variable[k]] = g_.lower[k] + (static_cast<double>(c % static_cast<std::size_t>(g_.cells[k])) + 0.5) * g_.cell[k];
        c /= static_cast<std::size_t>(g_.cells[k]);
      }
      model_.kinematics().compute(state_.data(), poses_);
      apart += !links_within(model_, a_, b_, poses_, settled_ + closing + kBoundMargin);
    }
    return static_cast<double>(apart) / static_cast<double>(n);
  }
  // Exact tests at most (fill stops past them; over_budget() then tells).
  void set_budget(std::size_t tests) { budget_ = tests; }
  bool over_budget() const { return tests_ > budget_; }
  std::size_t tests() const { return tests_; }
  // How far the pair can close from a cell's centre to its edge (per variable, half a cell).
  double cell_closing(const PairClearanceGrid& g) const {
    double closing = 0.0;
    for (int k = 0; k < g.dims; ++k) closing += 0.5 * g.cell[k] * rate_[k];
    return closing;
  }

 private:
  // The bound stored for a settled cell: this above the padding.
  static constexpr double kSettled = 1e-4;
  const RobotCollisionModel& model_;
  int a_, b_;
  PairClearanceGrid& g_;
  std::vector<double> state_;
  std::vector<Transform> poses_;
  std::array<double, PairClearanceGrid::kMaxDims> rate_{};
  double settled_ = 0.0;
  std::size_t tests_ = 0, budget_ = std::numeric_limits<std::size_t>::max();
};

// Worth a grid? Sampled on a coarse lattice (64 points), a pair within its padding in most of
// its range (a shoulder and the upper arm when no matrix allows them) would rarely be skipped:
// its grid would cost seconds of distances (pr2) for nothing. Only a choice of work, not of
// correctness.
bool mostly_touching(const RobotCollisionModel& model, int a, int b, const PairClearanceGrid& g) {
  const int per = g.dims == 1 ? 64 : g.dims == 2 ? 8 : 4;  // lattice points per variable
  std::vector<double> state(model.robot().variable_count(), 0.0);
  std::vector<Transform> poses;
  const double padding = model.paddings()[a] + model.paddings()[b];
  int touching = 0, total = 0;
  Cells hi{1, 1, 1};
  for (int k = 0; k < g.dims; ++k) hi[k] = per;
  for (int z = 0; z < hi[2]; ++z) {
    for (int y = 0; y < hi[1]; ++y) {
      for (int x = 0; x < hi[0]; ++x) {
        const Cells at{x, y, z};
        for (int k = 0; k < g.dims; ++k) state[g.variable[k]] = g.lower[k] + (at[k] + 0.5) / per * g.cell[k] * g.cells[k];
        model.kinematics().compute(state.data(), poses);
        touching += links_within(model, a, b, poses, padding);
        ++total;
      }
    }
  }
  return 2 * touching > total;
}

// A grid of one or two variables with cells left without a bound is built again with
// kRefinedCells times the budget when the finer cells would settle most of those (sampled: a pair
// that touches there gains nothing, and its finer grid would cost seconds on pr2).
void refine(const RobotCollisionModel& model, int a, int b, PairClearanceGrid& g, GridFiller& filler, std::size_t max_cells) {
  if (std::none_of(g.bound.begin(), g.bound.end(), [](float f) { return std::isinf(f); })) return;
  PairClearanceGrid fine = detail::refined_grid_shape(model, g, max_cells);
  if (fine.dims == 0) return;
  const auto open = std::count_if(g.bound.begin(), g.bound.end(), [](float f) { return std::isinf(f); });
  // More than a quarter of the cells open: the pair is close over much of its range, and the
  // finer grid would cost tests all over it (pr2's shoulders without an SRDF, solo's legs: a
  // second or more each).
  if (4 * static_cast<std::size_t>(open) > g.bound.size() || filler.share_apart(filler.cell_closing(fine), 64) < 0.5) return;
  // Bounded by the coarse grid's work: a pair whose finer cells need far more tests keeps the
  // coarse grid, at the cost of the tests spent.
  GridFiller fine_filler(model, a, b, fine);
  fine_filler.set_budget(filler.tests() + 8192);
  fine_filler.fill({0, 0, 0}, fine.cells);
  if (!fine_filler.over_budget()) g = std::move(fine);
}

}  // namespace

namespace detail {

std::vector<PairClearanceGrid> clearance_grid_shapes(const RobotCollisionModel& model, std::size_t max_cells) {
  std::vector<PairClearanceGrid> out;
  std::vector<int> vars;
  for (std::size_t p = 0; p < model.checked_pairs().size(); ++p) {
    const auto [a, b] = model.checked_pairs()[p];
    if (!path_variables(model.robot(), a, b, vars) || vars.empty() || vars.size() > PairClearanceGrid::kMaxDims) continue;
    PairClearanceGrid g = grid_shape(model, a, b, vars, std::max<std::size_t>(max_cells, 1));
    if (g.dims == 0) continue;
    g.pair = p;
    out.push_back(std::move(g));
  }
  return out;
}

PairClearanceGrid refined_grid_shape(const RobotCollisionModel& model, const PairClearanceGrid& coarse, std::size_t max_cells) {
  if (coarse.dims == 0 || coarse.dims > 2) return {};
  const auto [a, b] = model.checked_pairs()[coarse.pair];
  const std::vector<int> moved(coarse.variable.begin(), coarse.variable.begin() + coarse.dims);
  PairClearanceGrid fine = grid_shape(model, a, b, moved, std::max<std::size_t>(max_cells, 1) * PairClearance::kRefinedCells);
  if (fine.dims != coarse.dims || fine.cells[0] * fine.cells[1] <= coarse.cells[0] * coarse.cells[1]) return {};
  fine.pair = coarse.pair;
  return fine;
}

// Each pyramid cell the least of the up to 2^dims cells below it, until every variable has one cell.
void build_pyramid(PairClearanceGrid& g) {
  g.pyramid.clear();
  for (int level = 1;; ++level) {
    bool top = true;
    for (int k = 0; k < g.dims; ++k) top = top && g.cells_at(level - 1, k) == 1;
    if (top) return;
    const std::vector<float>& below = level == 1 ? g.bound : g.pyramid.back();
    const Cells n_below{g.cells_at(level - 1, 0), g.cells_at(level - 1, 1), g.cells_at(level - 1, 2)};
    const Cells n{g.cells_at(level, 0), g.cells_at(level, 1), g.cells_at(level, 2)};
    std::vector<float> out(static_cast<std::size_t>(n[0]) * n[1] * n[2], std::numeric_limits<float>::infinity());
    for (int z = 0; z < n_below[2]; ++z) {
      for (int y = 0; y < n_below[1]; ++y) {
        for (int x = 0; x < n_below[0]; ++x) {
          float& least = out[static_cast<std::size_t>(x / 2) + n[0] * (static_cast<std::size_t>(y / 2) + n[1] * static_cast<std::size_t>(z / 2))];
          least = std::min(least, below[static_cast<std::size_t>(x) + n_below[0] * (static_cast<std::size_t>(y) + n_below[1] * static_cast<std::size_t>(z))]);
        }
      }
    }
    g.pyramid.push_back(std::move(out));
  }
}

}  // namespace detail

PairClearance PairClearance::build(const RobotCollisionModel& model, std::size_t max_cells) {
  const auto start = std::chrono::steady_clock::now();
  // The grids' shapes first (cheap), then their cells on the shared pool: pairs cost from
  // microseconds to a quarter second (pr2's elbow), so they are taken one at a time.
  std::vector<PairClearanceGrid> candidates = detail::clearance_grid_shapes(model, max_cells);
  std::vector<char> kept(candidates.size(), 0);
  ThreadPool::shared().for_each(candidates.size(), 1, [&](std::size_t i) {
    PairClearanceGrid& g = candidates[i];
    const auto [a, b] = model.checked_pairs()[g.pair];
    if (mostly_touching(model, a, b, g)) return;
    GridFiller filler(model, a, b, g);
    filler.fill({0, 0, 0}, g.cells);
    if (g.dims <= 2) refine(model, a, b, g, filler, max_cells);
    detail::build_pyramid(g);
    kept[i] = 1;
  });
  PairClearance out;
  out.grid_of_.assign(model.checked_pairs().size(), -1);
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (!kept[i]) continue;
    out.grid_of_[candidates[i].pair] = static_cast<int>(out.grids_.size());
    out.grids_.push_back(std::move(candidates[i]));
  }
  out.build_seconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return out;
}

double PairClearance::grid_bound(const PairClearanceGrid& g, const double* state) {
  std::size_t index = 0, stride = 1;
  for (int k = 0; k < g.dims; ++k) {
    double x = state[g.variable[k]] - g.lower[k];
    const double span = g.cell[k] * g.cells[k];
    if (g.periodic[k]) x -= kTwoPi * std::floor(x / kTwoPi);
    // A value beyond the grid (or NaN) has no bound; the upper edge belongs to the last cell.
    if (!(x >= 0.0 && x <= span)) return -std::numeric_limits<double>::infinity();
    const int i = std::min(static_cast<int>(x / g.cell[k]), g.cells[k] - 1);
    index += static_cast<std::size_t>(i) * stride;
    stride *= static_cast<std::size_t>(g.cells[k]);
  }
  return g.bound[index];
}

namespace {

// Points of a segment whose cells are looked up before its proof (and the end).
constexpr int kProbes = 8;

// The segment's position in units of the finest cells, per grid variable, at fraction t.
struct SegmentInCells {
  std::array<double, PairClearanceGrid::kMaxDims> from{}, step{};
  double at(int k, double t) const { return from[k] + t * step[k]; }
};

// Proves the part [t0, t1] of the segment clear, from pyramid level `level` down (0: `bound`):
// the level's cells that the part's box spans, widened by `kEdge` of a cell (a value computed on
// a cell's edge may round either way), when at most two per variable (the part halved at this
// level otherwise); when one of those holds no more than `clearance`, the next finer level's
// (at the finest, each half of the part on its own).
class SegmentProof {
 public:
  SegmentProof(const PairClearanceGrid& g, const SegmentInCells& s, double clearance, int max_visits)
      : g_(g), s_(s), clearance_(clearance), visits_left_(max_visits) {}

  bool clear(double t0, double t1, int level) {
    if (--visits_left_ < 0) return false;
    Cells lo{0, 0, 0}, hi{0, 0, 0};
    bool narrow = true;
    for (int k = 0; k < g_.dims; ++k) {
      const double u0 = s_.at(k, t0), u1 = s_.at(k, t1);
      const double scale = 1.0 / static_cast<double>(1 << level);  // exact
      const int last = g_.cells_at(level, k) - 1;
      // (Truncation is the floor here: the values are at least -kEdge, and the clamp takes the
      // rest. std::floor is a library call without SSE4.1.)
      lo[k] = std::clamp(static_cast<int>((std::min(u0, u1) - kEdge) * scale), 0, last);
      hi[k] = std::clamp(static_cast<int>((std::max(u0, u1) + kEdge) * scale), 0, last);
      narrow = narrow && hi[k] - lo[k] <= 1;
    }
    if (!narrow) {
      const double mid = 0.5 * (t0 + t1);
      return clear(t0, mid, level) && clear(mid, t1, level);
    }
    if (box_clear(lo, hi, level)) return true;
    // At the finest level a box of two cells where the part is long may hold a cell it does not
    // cross (a corner it passes by): halved once more. Short, the cell it cannot avoid decides.
    double length = 0.0;
    for (int k = 0; k < g_.dims; ++k) length = std::max(length, std::abs(s_.at(k, t1) - s_.at(k, t0)));
    if (level == 0 && (lo == hi || length <= 0.5)) return false;
    // A level down, the whole part's box where it is still narrow there (clear halves it
    // otherwise): halving the part at every level doubled the boxes at each level down, and on
    // panda's wrist grids, whose proofs mostly hold a few levels below the top, spent the budget:
    // 15 boxes a proof and one proof in ten given up (docs/performance.md).
    if (level > 0) return clear(t0, t1, level - 1);
    const double mid = 0.5 * (t0 + t1);
    return clear(t0, mid, 0) && clear(mid, t1, 0);
  }

 private:
  static constexpr double kEdge = 1e-9;

  bool box_clear(const Cells& lo, const Cells& hi, int level) const {
    const std::vector<float>& bound = level == 0 ? g_.bound : g_.pyramid[static_cast<std::size_t>(level) - 1];
    const std::size_t nx = static_cast<std::size_t>(g_.cells_at(level, 0)), ny = static_cast<std::size_t>(g_.cells_at(level, 1));
    for (int z = lo[2]; z <= hi[2]; ++z) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int x = lo[0]; x <= hi[0]; ++x) {
          if (!(static_cast<double>(bound[static_cast<std::size_t>(x) + nx * (y + ny * static_cast<std::size_t>(z))]) > clearance_)) return false;
        }
      }
    }
    return true;
  }

  const PairClearanceGrid& g_;
  const SegmentInCells& s_;
  double clearance_;
  int visits_left_;
};

// A segment proof's budget of boxes: this many a finest cell the segment crosses, at most kMaxBoxes.
constexpr double kBoxesPerCellCrossed = 8.0;
constexpr double kMaxBoxes = 4096.0;

}  // namespace

bool PairClearance::clear_over(std::size_t pair, const double* a, const double* b, double clearance, int max_visits) const {
  const int id = grid_of_.empty() ? -1 : grid_of_[pair];
  if (id < 0) return false;
  const PairClearanceGrid& g = grids_[id];
  SegmentInCells s;
  for (int k = 0; k < g.dims; ++k) {
    if (g.periodic[k]) return false;
    const double span = g.cell[k] * g.cells[k];
    const double u0 = a[g.variable[k]] - g.lower[k], u1 = b[g.variable[k]] - g.lower[k];
    if (!(u0 >= 0.0 && u0 <= span && u1 >= 0.0 && u1 <= span)) return false;
    s.from[k] = u0 / g.cell[k];
    s.step[k] = u1 / g.cell[k] - s.from[k];
  }
  // A grid settled everywhere (its coarsest cell) proves any segment within it.
  const std::vector<float>& top = g.pyramid.empty() ? g.bound : g.pyramid.back();
  if (top.size() == 1 && static_cast<double>(top[0]) > clearance) return true;
  // A segment through a cell with no bound mostly meets it at one of a few points along it: those
  // cells first, each one lookup (a failed proof that walked the pyramid first took hundreds of
  // boxes along the cells it could prove).
  for (int i = 0; i <= kProbes; ++i) {
    const double t = static_cast<double>(i) / kProbes;
    std::size_t index = 0, stride = 1;
    for (int k = 0; k < g.dims; ++k) {
      const int c = std::clamp(static_cast<int>(s.at(k, t)), 0, g.cells[k] - 1);
      index += static_cast<std::size_t>(c) * stride;
      stride *= static_cast<std::size_t>(g.cells[k]);
    }
    if (!(static_cast<double>(g.bound[index]) > clearance)) return false;
  }
  // A segment through many cells needs boxes in proportion where the coarse levels cannot settle
  // it: its budget grows with the finest cells it crosses (a fixed 32 gave up on long segments
  // that a few more boxes prove: docs/performance.md).
  double crossed = 1.0;
  for (int k = 0; k < g.dims; ++k) crossed += std::abs(s.step[k]);
  max_visits = std::max(max_visits, static_cast<int>(std::min(kMaxBoxes, kBoxesPerCellCrossed * crossed)));
  return SegmentProof(g, s, clearance, max_visits).clear(0.0, 1.0, static_cast<int>(g.pyramid.size()));
}

std::size_t PairClearance::memory_bytes() const {
  std::size_t bytes = grid_of_.capacity() * sizeof(int);
  for (const PairClearanceGrid& g : grids_) {
    bytes += sizeof(g) + g.bound.capacity() * sizeof(float);
    for (const auto& level : g.pyramid) bytes += level.capacity() * sizeof(float);
  }
  return bytes;
}

}  // namespace bvh_collision
