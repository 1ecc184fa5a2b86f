#include "bvh_collision/model/pair_clearance_cache.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>

#include "bvh_collision/model/detail/pair_clearance_shape.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/narrowphase/cache_file.h"

namespace bvh_collision {
namespace {

constexpr char kMagic[8] = {'B', 'V', 'H', 'G', 'R', 'I', 'D', 'S'};

std::size_t cell_count(const PairClearanceGrid& g) {
  return static_cast<std::size_t>(g.cells[0]) * static_cast<std::size_t>(g.cells[1]) * static_cast<std::size_t>(g.cells[2]);
}

}  // namespace

// The file: magic, version, key, the number of checked pairs, the number of grids, then per grid
// its pair, its cell counts and its cells' bounds (floats), then a checksum of everything before
// it. A grid's variables and range are not stored: they are the build's shape for its pair.
struct PairClearanceFile {
  static std::string encode(const PairClearance& c, std::uint64_t key) {
    std::string out(kMagic, sizeof kMagic);
    put_value(out, kPairClearanceBuildVersion);
    put_value(out, key);
    put_value(out, static_cast<std::uint64_t>(c.grid_of_.size()));
    put_value(out, static_cast<std::uint64_t>(c.grids_.size()));
    for (const PairClearanceGrid& g : c.grids_) {
      put_value(out, static_cast<std::uint64_t>(g.pair));
      for (int k = 0; k < PairClearanceGrid::kMaxDims; ++k) put_value(out, static_cast<std::int32_t>(g.cells[k]));
      out.append(reinterpret_cast<const char*>(g.bound.data()), g.bound.size() * sizeof(float));
    }
    seal(out);
    return out;
  }

  // The grids, when the bytes are ones written for `key` and every grid is the shape the build
  // gives its pair of `model` (the coarse one or its refinement), its bounds a number or -infinity.
  static std::optional<PairClearance> decode(const std::string& in, std::uint64_t key, const RobotCollisionModel& model,
                                             std::size_t max_cells) {
    if (in.size() < sizeof kMagic || std::memcmp(in.data(), kMagic, sizeof kMagic) != 0 || !sealed(in)) return std::nullopt;
    const std::size_t end = in.size() - sizeof(std::uint64_t);  // the checksum's start
    std::size_t at = sizeof kMagic;
    std::uint32_t version = 0;
    std::uint64_t stored_key = 0, pairs = 0, count = 0;
    if (!take_value(in, at, version) || version != kPairClearanceBuildVersion || !take_value(in, at, stored_key) ||
        stored_key != key || !take_value(in, at, pairs) || pairs != model.checked_pairs().size() ||
        !take_value(in, at, count)) {
      return std::nullopt;
    }
    const std::vector<PairClearanceGrid> shapes = detail::clearance_grid_shapes(model, max_cells);
    if (count > shapes.size()) return std::nullopt;
    PairClearance out;
    out.grid_of_.assign(pairs, -1);
    std::size_t next_shape = 0;  // grids are stored in pair order, as the build keeps them
    for (std::uint64_t i = 0; i < count; ++i) {
      std::uint64_t pair = 0;
      std::array<std::int32_t, PairClearanceGrid::kMaxDims> cells{};
      if (!take_value(in, at, pair)) return std::nullopt;
      for (std::int32_t& c : cells) {
        if (!take_value(in, at, c)) return std::nullopt;
      }
      while (next_shape < shapes.size() && shapes[next_shape].pair < pair) ++next_shape;
      if (next_shape == shapes.size() || shapes[next_shape].pair != pair) return std::nullopt;
      PairClearanceGrid g = shapes[next_shape++];
      if (std::equal(cells.begin(), cells.end(), g.cells.begin()) == false) {
        g = detail::refined_grid_shape(model, g, max_cells);
        if (g.dims == 0 || !std::equal(cells.begin(), cells.end(), g.cells.begin())) return std::nullopt;
      }
      const std::size_t n = cell_count(g);
      if (end - at < n * sizeof(float)) return std::nullopt;
      g.bound.resize(n);
      std::memcpy(g.bound.data(), in.data() + at, n * sizeof(float));
      at += n * sizeof(float);
      for (const float f : g.bound) {
        if (std::isnan(f) || f == std::numeric_limits<float>::infinity()) return std::nullopt;
      }
      detail::build_pyramid(g);
      out.grid_of_[g.pair] = static_cast<int>(out.grids_.size());
      out.grids_.push_back(std::move(g));
    }
    if (at != end) return std::nullopt;
    out.from_cache_ = true;
    return out;
  }

  static void set_seconds(PairClearance& c, double seconds) { c.build_seconds_ = seconds; }
};

std::uint64_t pair_clearance_key(const RobotCollisionModel& model, std::size_t max_cells) {
  ContentHash h;
  h.value(kPairClearanceBuildVersion);
  h.value(static_cast<std::uint64_t>(max_cells));
  h.value(static_cast<std::uint64_t>(model.robot().variable_count()));
  h.value(static_cast<std::uint64_t>(model.shapes().size()));
  for (std::size_t l = 0; l < model.shapes().size(); ++l) {
    h.value(model.robot().links()[l].parent_joint);
    h.value(model.paddings()[l]);
    h.shapes(model.placed_shapes(static_cast<int>(l)));
    for (const double rate : model.motion_rates()[l]) h.value(rate);
  }
  h.value(static_cast<std::uint64_t>(model.robot().joints().size()));
  for (const RobotJoint& j : model.robot().joints()) {
    h.value(static_cast<int>(j.type));
    h.value(j.parent_link), h.value(j.child_link), h.value(j.variable), h.value(j.mimic);
    h.transform(j.origin);
    h.vec(j.axis);
    h.value(j.lower), h.value(j.upper), h.value(j.bounded), h.value(j.multiplier), h.value(j.offset);
  }
  h.value(static_cast<std::uint64_t>(model.checked_pairs().size()));
  for (const auto& [a, b] : model.checked_pairs()) h.value(a), h.value(b);
  return h.h;
}

std::string pair_clearance_file(const std::string& folder, std::uint64_t key) { return cache_file(folder, key, ".grids"); }

std::optional<PairClearance> read_cached_pair_clearance(const std::string& folder, std::uint64_t key,
                                                        const RobotCollisionModel& model, std::size_t max_cells) {
  const std::optional<std::string> bytes = read_cache_file(pair_clearance_file(folder, key));
  if (!bytes) return std::nullopt;
  return PairClearanceFile::decode(*bytes, key, model, max_cells);
}

bool write_cached_pair_clearance(const std::string& folder, std::uint64_t key, const PairClearance& grids) {
  return replace_cache_file(pair_clearance_file(folder, key), PairClearanceFile::encode(grids, key));
}

PairClearance cached_or_built_pair_clearance(const RobotCollisionModel& model, std::size_t max_cells,
                                             const std::string& folder) {
  if (folder.empty()) return PairClearance::build(model, max_cells);
  const auto start = std::chrono::steady_clock::now();
  const std::uint64_t key = pair_clearance_key(model, max_cells);
  if (std::optional<PairClearance> cached = read_cached_pair_clearance(folder, key, model, max_cells)) {
    PairClearanceFile::set_seconds(*cached, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    return std::move(*cached);
  }
  PairClearance built = PairClearance::build(model, max_cells);
  write_cached_pair_clearance(folder, key, built);  // a cache that cannot be written only costs time
  return built;
}

}  // namespace bvh_collision
