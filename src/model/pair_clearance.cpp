#include "bvh_collision/model/pair_clearance.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "bvh_collision/model/robot_collision_model.h"
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

}  // namespace

PairClearance PairClearance::build(const RobotCollisionModel& model, std::size_t max_cells) {
  const auto start = std::chrono::steady_clock::now();
  // The grids' shapes first (cheap), then their cells on the shared pool: pairs cost from
  // microseconds to a quarter second (pr2's elbow), so they are taken one at a time.
  std::vector<PairClearanceGrid> candidates;
  std::vector<int> vars;
  for (std::size_t p = 0; p < model.checked_pairs().size(); ++p) {
    const auto [a, b] = model.checked_pairs()[p];
    if (!path_variables(model.robot(), a, b, vars) || vars.empty() || vars.size() > PairClearanceGrid::kMaxDims) continue;
    PairClearanceGrid g = grid_shape(model, a, b, vars, std::max<std::size_t>(max_cells, 1));
    if (g.dims == 0) continue;
    g.pair = p;
    candidates.push_back(std::move(g));
  }
  std::vector<char> kept(candidates.size(), 0);
  ThreadPool::shared().for_each(candidates.size(), 1, [&](std::size_t i) {
    PairClearanceGrid& g = candidates[i];
    const auto [a, b] = model.checked_pairs()[g.pair];
    if (mostly_touching(model, a, b, g)) return;
    GridFiller(model, a, b, g).fill({0, 0, 0}, g.cells);
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

double PairClearance::lower_bound_over(std::size_t pair, const double* a, const double* b, std::size_t max_cells) const {
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  const int id = grid_of_.empty() ? -1 : grid_of_[pair];
  if (id < 0) return kNone;
  const PairClearanceGrid& g = grids_[id];
  Cells first{0, 0, 0}, end{1, 1, 1};
  std::size_t cells = 1;
  for (int k = 0; k < g.dims; ++k) {
    if (g.periodic[k]) return kNone;
    const double lo = std::min(a[g.variable[k]], b[g.variable[k]]) - g.lower[k];
    const double hi = std::max(a[g.variable[k]], b[g.variable[k]]) - g.lower[k];
    if (!(lo >= 0.0 && hi <= g.cell[k] * g.cells[k])) return kNone;
    first[k] = std::min(static_cast<int>(lo / g.cell[k]), g.cells[k] - 1);
    end[k] = std::min(static_cast<int>(hi / g.cell[k]), g.cells[k] - 1) + 1;
    cells *= static_cast<std::size_t>(end[k] - first[k]);
  }
  if (cells > max_cells) return kNone;
  double bound = std::numeric_limits<double>::infinity();
  for_each_cell(g, first, end, [&](std::size_t c) { bound = std::min(bound, static_cast<double>(g.bound[c])); });
  return bound;
}

std::size_t PairClearance::memory_bytes() const {
  std::size_t bytes = grid_of_.capacity() * sizeof(int);
  for (const PairClearanceGrid& g : grids_) bytes += sizeof(g) + g.bound.capacity() * sizeof(float);
  return bytes;
}

}  // namespace bvh_collision
