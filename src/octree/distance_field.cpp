// OctreeDistanceField (octree/distance_field.h): the grid, the occupied voxels from the tree's
// leaves, and the exact squared distance transform, one axis at a time.
#include "bvh_collision/octree/distance_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {
namespace {

constexpr std::uint32_t kFar = std::numeric_limits<std::uint32_t>::max();

// A breakpoint of the lower envelope, num / den with den > 0, or +-infinity.
struct Breakpoint {
  std::int64_t num = 0, den = 1;
  int infinite = 0;  // -1, 0, +1
};
bool less_equal(const Breakpoint& a, const Breakpoint& b) {
  if (a.infinite != 0 || b.infinite != 0) return a.infinite == -1 || b.infinite == 1;
  return a.num * b.den <= b.num * a.den;
}
bool less_than(const Breakpoint& a, std::int64_t q) {
  if (a.infinite != 0) return a.infinite == -1;
  return a.num < q * a.den;
}

// d(q) = min over p with f(p) finite of (q - p)^2 + f(p), f and d over `count` values `stride`
// apart (Felzenszwalb and Huttenlocher's lower envelope of parabolas, with the intersections
// kept as exact fractions: every value is an integer below 2^40, so their products fit).
void transform_line(std::uint32_t* line, std::int64_t count, std::int64_t stride, std::vector<std::int64_t>& f,
                    std::vector<std::int64_t>& v, std::vector<Breakpoint>& z) {
  f.resize(count);
  v.resize(count);
  z.resize(count + 1);
  for (std::int64_t q = 0; q < count; ++q) f[q] = line[q * stride] == kFar ? -1 : std::int64_t(line[q * stride]);
  std::int64_t k = -1;
  for (std::int64_t q = 0; q < count; ++q) {
    if (f[q] < 0) continue;
    Breakpoint s;
    while (k >= 0) {
      const std::int64_t p = v[k];
      s = {(f[q] + q * q) - (f[p] + p * p), 2 * (q - p), 0};  // where q's parabola goes below p's
      if (!less_equal(s, z[k])) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? Breakpoint{0, 1, -1} : s;
    z[k + 1] = Breakpoint{0, 1, 1};
  }
  if (k < 0) return;  // no occupied voxel on the line: it stays kFar
  k = 0;
  for (std::int64_t q = 0; q < count; ++q) {
    while (less_than(z[k + 1], q)) ++k;
    const std::int64_t d = (q - v[k]) * (q - v[k]) + f[v[k]];
    line[q * stride] = static_cast<std::uint32_t>(std::min<std::int64_t>(d, kFar - 1));
  }
}

std::int64_t voxel_of(double x, double resolution) { return static_cast<std::int64_t>(std::floor(x / resolution)); }
// The same through a multiplication (queries): at most an ulp or two from x / res, so a point
// lands in the other voxel only within rounding of their shared face, which the margins cover.
std::int64_t voxel_at(double x, double inverse) { return static_cast<std::int64_t>(std::floor(x * inverse)); }

}  // namespace

OctreeDistanceField OctreeDistanceField::build(const Octree& tree, const Vec3& lo, const Vec3& hi, double cap,
                                               std::size_t max_cells) {
  if (!lo.allFinite() || !hi.allFinite() || (hi - lo).minCoeff() < 0.0) {
    throw std::invalid_argument("distance field: the box must be finite and not empty");
  }
  if (!(cap > 0.0) || !std::isfinite(cap)) throw std::invalid_argument("distance field: the cap must be positive and finite");
  OctreeDistanceField field;
  const double res = tree.resolution();
  field.resolution_ = res;
  field.inverse_ = 1.0 / res;
  field.cap_ = cap;
  const std::int64_t pad = static_cast<std::int64_t>(std::ceil(cap / res)) + 1;
  std::size_t cells = 1;
  for (int a = 0; a < 3; ++a) {
    field.inner_lo_[a] = voxel_of(lo[a], res);
    field.inner_hi_[a] = voxel_of(hi[a], res);
    field.grid_lo_[a] = field.inner_lo_[a] - pad;
    field.size_[a] = field.inner_hi_[a] - field.inner_lo_[a] + 1 + 2 * pad;
    if (field.size_[a] > 60000 || cells * std::size_t(field.size_[a]) > max_cells) {
      throw std::invalid_argument("distance field: the box and cap need more than " + std::to_string(max_cells) +
                                  " cells at this resolution");
    }
    cells *= std::size_t(field.size_[a]);
  }
  // Written in the grid's file before any version of it exists: nothing to keep.
  const std::shared_ptr<VersionedGrid> grid = VersionedGrid::create(cells, kFar);
  std::uint32_t* d = grid->head();
  const std::int64_t sx = field.size_[0], sy = field.size_[1], sz = field.size_[2];
  auto at = [&](std::int64_t x, std::int64_t y, std::int64_t z) { return (x * sy + y) * sz + z; };
  // The occupied voxels: every voxel of each occupied leaf (a pruned leaf is a cube of them).
  const Vec3 grid_min = Vec3(double(field.grid_lo_[0]), double(field.grid_lo_[1]), double(field.grid_lo_[2])) * res;
  const Vec3 grid_max = grid_min + Vec3(double(sx), double(sy), double(sz)) * res;
  for (const Octree::Leaf& leaf : tree.occupied_in_box(grid_min, grid_max)) {
    const std::int64_t side = std::int64_t(1) << (kOctreeDepth - leaf.depth);
    std::int64_t b[3], e[3];
    for (int a = 0; a < 3; ++a) {
      const std::int64_t first = std::int64_t(leaf.key.k[a]) - kOctreeKeyOffset - field.grid_lo_[a];
      b[a] = std::max<std::int64_t>(0, first);
      e[a] = std::min<std::int64_t>(field.size_[a], first + side);
    }
    for (std::int64_t x = b[0]; x < e[0]; ++x) {
      for (std::int64_t y = b[1]; y < e[1]; ++y) {
        for (std::int64_t z = b[2]; z < e[2]; ++z) d[at(x, y, z)] = 0;
      }
    }
  }
  // The bound of every squared centre distance below the cap's, computed once (a query then
  // takes one load instead of a square root).
  for (std::uint32_t d = 0;; ++d) {
    const double bound = std::min((std::sqrt(double(d)) - std::sqrt(3.0)) * res, cap);
    field.bound_of_squared_.push_back(bound);
    if (bound >= cap) break;
  }
  // Separable: along z, then y, then x (a squared distance sums its axes' squares).
  std::vector<std::int64_t> f, v;
  std::vector<Breakpoint> zs;
  for (std::int64_t x = 0; x < sx; ++x) {
    for (std::int64_t y = 0; y < sy; ++y) transform_line(d + at(x, y, 0), sz, 1, f, v, zs);
  }
  for (std::int64_t x = 0; x < sx; ++x) {
    for (std::int64_t z = 0; z < sz; ++z) transform_line(d + at(x, 0, z), sy, sz, f, v, zs);
  }
  for (std::int64_t y = 0; y < sy; ++y) {
    for (std::int64_t z = 0; z < sz; ++z) transform_line(d + at(0, y, z), sx, sy * sz, f, v, zs);
  }
  const std::uint32_t clamp = static_cast<std::uint32_t>(field.bound_of_squared_.size() - 1);
  for (std::size_t i = 0; i < cells; ++i) d[i] = std::min(d[i], clamp);
  field.adopt(grid);
  return field;
}

namespace {

constexpr std::int64_t kBlock = 16;  // an update's unit of recomputation, per axis

// The squared distance along one line to the nearest occupied cell (0 in `occupied_at`) within
// [0, count), for the positions [from, to): two sweeps. kFar where the line holds none.
template <class Occupied>
void nearest_along(std::int64_t count, std::int64_t from, std::int64_t to, Occupied&& occupied_at, std::uint32_t* out) {
  std::int64_t last = -1;
  std::int64_t q = 0;
  for (; q < from; ++q) {
    if (occupied_at(q)) last = q;
  }
  // The nearest at or before each position, then the nearest after it (scanning on to `count`).
  for (; q < to; ++q) {
    if (occupied_at(q)) last = q;
    out[q - from] = last < 0 ? kFar : static_cast<std::uint32_t>((q - last) * (q - last));
  }
  std::int64_t next = -1;
  for (q = to; q < count && next < 0; ++q) {
    if (occupied_at(q)) next = q;
  }
  for (q = to - 1; q >= from; --q) {
    if (occupied_at(q)) next = q;
    if (next >= 0) out[q - from] = std::min(out[q - from], static_cast<std::uint32_t>((next - q) * (next - q)));
  }
}

}  // namespace

// One block's cells [lo, hi) from the occupancy within `reach` of it (the window): along z to
// the block's z range, then along y, then x, each pass over the window's lines.
void OctreeDistanceField::recompute_block(const std::int64_t lo[3], const std::int64_t hi[3], std::int64_t reach,
                                          VersionedGrid& grid, UpdateWork& work) const {
  std::uint32_t* const cells = grid.head();
  std::int64_t wlo[3], whi[3], n[3];
  for (int a = 0; a < 3; ++a) {
    wlo[a] = std::max<std::int64_t>(0, lo[a] - reach);
    whi[a] = std::min<std::int64_t>(size_[a], hi[a] + reach);
    n[a] = hi[a] - lo[a];
  }
  const std::int64_t wx = whi[0] - wlo[0], wy = whi[1] - wlo[1];
  thread_local std::vector<std::uint32_t> g1, g2, line;
  thread_local std::vector<std::int64_t> f, v;
  thread_local std::vector<Breakpoint> zs;
  g1.assign(std::size_t(wx * wy * n[2]), kFar);  // [x][y][z] over the window's x, y
  for (std::int64_t x = 0; x < wx; ++x) {
    for (std::int64_t y = 0; y < wy; ++y) {
      const std::uint32_t* row = cells + index(wlo[0] + x, wlo[1] + y, 0);
      // (Window-relative: the column is read over the window only, not from the grid's start.)
      nearest_along(whi[2] - wlo[2], lo[2] - wlo[2], hi[2] - wlo[2], [&](std::int64_t z) { return row[wlo[2] + z] == 0; },
                    &g1[std::size_t((x * wy + y) * n[2])]);
    }
  }
  work.window_cells += std::size_t(wx * wy * (whi[2] - wlo[2]));
  g2.assign(std::size_t(wx * n[1] * n[2]), kFar);  // [x][y][z] over the window's x
  line.resize(std::size_t(std::max(wx, wy)));
  for (std::int64_t x = 0; x < wx; ++x) {
    for (std::int64_t z = 0; z < n[2]; ++z) {
      for (std::int64_t y = 0; y < wy; ++y) line[y] = g1[std::size_t((x * wy + y) * n[2] + z)];
      transform_line(line.data(), wy, 1, f, v, zs);
      for (std::int64_t y = 0; y < n[1]; ++y) g2[std::size_t((x * n[1] + y) * n[2] + z)] = line[lo[1] + y - wlo[1]];
    }
  }
  const std::uint32_t clamp = static_cast<std::uint32_t>(bound_of_squared_.size() - 1);
  for (std::int64_t y = 0; y < n[1]; ++y) {
    for (std::int64_t z = 0; z < n[2]; ++z) {
      for (std::int64_t x = 0; x < wx; ++x) line[x] = g2[std::size_t((x * n[1] + y) * n[2] + z)];
      transform_line(line.data(), wx, 1, f, v, zs);
      for (std::int64_t x = 0; x < n[0]; ++x) {
        // Only a changed value is written: a page no value of changes is not kept for older versions.
        const std::size_t i = std::size_t(index(lo[0] + x, lo[1] + y, lo[2] + z));
        const std::uint32_t value = std::min(line[lo[0] + x - wlo[0]], clamp);
        if (cells[i] == value) continue;
        grid.keep_before_write(i);
        cells[i] = value;
        ++work.changed_cells;
      }
    }
  }
  ++work.blocks;
  work.cells += std::size_t(n[0] * n[1] * n[2]);
}

// The flipped voxels of `flipped` inside the grid, and the blocks within the cap's reach of each.
struct OctreeDistanceField::Change {
  std::vector<char> dirty;                                     // per block
  std::vector<std::pair<std::int64_t, const OctreeKey*>> inside;  // (cell, key)
  std::size_t dirty_blocks = 0;
  std::int64_t blocks[3] = {0, 0, 0};
};

OctreeDistanceField::Change OctreeDistanceField::change_of(const std::vector<const std::vector<OctreeKey>*>& flipped) const {
  Change c;
  const std::int64_t reach = this->reach();
  for (int a = 0; a < 3; ++a) c.blocks[a] = (size_[a] + kBlock - 1) / kBlock;
  c.dirty.assign(std::size_t(c.blocks[0] * c.blocks[1] * c.blocks[2]), 0);
  for (const std::vector<OctreeKey>* list : flipped) {
    for (const OctreeKey& key : *list) {
      std::int64_t v[3], b0[3], b1[3];
      for (int a = 0; a < 3; ++a) v[a] = std::int64_t(key.k[a]) - kOctreeKeyOffset - grid_lo_[a];
      if (!(v[0] >= 0 && v[0] < size_[0] && v[1] >= 0 && v[1] < size_[1] && v[2] >= 0 && v[2] < size_[2])) continue;
      c.inside.emplace_back(index(v[0], v[1], v[2]), &key);
      for (int a = 0; a < 3; ++a) {
        b0[a] = std::max<std::int64_t>(0, v[a] - reach) / kBlock;
        b1[a] = std::min<std::int64_t>(size_[a] - 1, v[a] + reach) / kBlock;
      }
      for (std::int64_t x = b0[0]; x <= b1[0]; ++x) {
        for (std::int64_t y = b0[1]; y <= b1[1]; ++y) {
          std::fill_n(&c.dirty[std::size_t((x * c.blocks[1] + y) * c.blocks[2] + b0[2])], b1[2] - b0[2] + 1, 1);
        }
      }
    }
  }
  c.dirty_blocks = static_cast<std::size_t>(std::count(c.dirty.begin(), c.dirty.end(), 1));
  return c;
}

// A block's window costs about 25 cell passes a cell, a build about 3 over the grid: past an
// eighth of the grid, a build is cheaper (the same values).
bool OctreeDistanceField::build_is_cheaper(const Change& change) const {
  return change.dirty_blocks * std::size_t(kBlock * kBlock * kBlock) * 8 > cells_;
}

OctreeDistanceField OctreeDistanceField::rebuilt(const Octree& tree, std::size_t flipped, UpdateWork* work) const {
  Vec3 lo = Vec3::Zero(), hi = Vec3::Zero();  // the centres of the box's first and last voxels
  for (int a = 0; a < 3; ++a) {
    lo[a] = (static_cast<double>(inner_lo_[a]) + 0.5) * resolution_;
    hi[a] = (static_cast<double>(inner_hi_[a]) + 0.5) * resolution_;
  }
  if (work != nullptr) {
    *work = UpdateWork{};
    work->flipped = flipped;
    work->rebuilt = true;
    work->cells = cells_;
  }
  return build(tree, lo, hi, cap_, cells_);
}

// The changed voxels' new occupancy (0: occupied; a freed one at the clamp, which its block's
// recomputation replaces), then the blocks.
void OctreeDistanceField::apply(const Octree& tree, const Change& change, VersionedGrid& grid, UpdateWork& work) const {
  const std::uint32_t clamp = static_cast<std::uint32_t>(bound_of_squared_.size() - 1);
  std::uint32_t* const cells = grid.head();
  for (const auto& [cell, key] : change.inside) {
    const auto found = tree.find(*key);
    const std::uint32_t value = found && tree.occupied(found->log_odds) ? 0 : clamp;
    if (cells[std::size_t(cell)] == value) continue;
    grid.keep_before_write(std::size_t(cell));
    cells[std::size_t(cell)] = value;
  }
  const std::int64_t reach = this->reach();
  for (std::int64_t x = 0; x < change.blocks[0]; ++x) {
    for (std::int64_t y = 0; y < change.blocks[1]; ++y) {
      for (std::int64_t z = 0; z < change.blocks[2]; ++z) {
        if (!change.dirty[std::size_t((x * change.blocks[1] + y) * change.blocks[2] + z)]) continue;
        const std::int64_t lo[3] = {x * kBlock, y * kBlock, z * kBlock};
        const std::int64_t hi[3] = {std::min(size_[0], lo[0] + kBlock), std::min(size_[1], lo[1] + kBlock), std::min(size_[2], lo[2] + kBlock)};
        recompute_block(lo, hi, reach, grid, work);
      }
    }
  }
}

OctreeDistanceField OctreeDistanceField::updated(const Octree& tree, const std::vector<OctreeKey>& flipped,
                                                 UpdateWork* work) const {
  return updated(tree, std::vector<const std::vector<OctreeKey>*>{&flipped}, work);
}

OctreeDistanceField OctreeDistanceField::updated(const Octree& tree, const std::vector<const std::vector<OctreeKey>*>& flipped,
                                                 UpdateWork* work, bool in_place) const {
  if (cells_ == 0) return *this;
  const Change change = change_of(flipped);
  if (build_is_cheaper(change)) return rebuilt(tree, change.inside.size(), work);
  UpdateWork counted;
  counted.flipped = change.inside.size();
  OctreeDistanceField out = *this;  // the bounds; the cells are the next version's
  const std::shared_ptr<VersionedGrid>& grid = version_->grid();
  std::unique_lock<std::mutex> writer(grid->writer());
  if (in_place && grid->head_version() == version_->id()) {  // in place: this field and older ones keep their pages
    const std::size_t kept = grid->kept_pages();
    try {
      apply(tree, change, *grid, counted);
    } catch (...) {  // half written: every version kept its pages, but the file is no version's
      grid->abandon_head();
      throw;
    }
    counted.kept_pages = grid->kept_pages() - kept;
    out.adopt(grid);
  } else {  // a newer field was made over this one's file: a grid of its own
    writer.unlock();
    const std::shared_ptr<VersionedGrid> copy = VersionedGrid::create(cells_, 0);
    std::copy_n(squared_, cells_, copy->head());
    counted.copied_cells = cells_;
    apply(tree, change, *copy, counted);
    out.adopt(copy);
  }
  if (work != nullptr) *work = counted;
  return out;
}

void OctreeDistanceField::follow(const Octree& tree, const std::vector<const std::vector<OctreeKey>*>& flipped,
                                 UpdateWork* work) {
  if (cells_ == 0) return;
  const Change change = change_of(flipped);
  const std::shared_ptr<VersionedGrid> grid = version_->grid();
  std::unique_lock<std::mutex> writer(grid->writer());
  if (build_is_cheaper(change) || !grid->begin_writing_over(version_)) {
    writer.unlock();
    *this = updated(tree, flipped, work);
    return;
  }
  UpdateWork counted;
  counted.flipped = change.inside.size();
  const std::size_t kept = grid->kept_pages();
  try {
    apply(tree, change, *grid, counted);
  } catch (...) {  // half written: this field reads as empty (nothing known), the grid as no one's
    grid->abandon_head();
    *this = OctreeDistanceField();
    throw;
  }
  counted.kept_pages = grid->kept_pages() - kept;
  grid->end_writing_over();
  if (work != nullptr) *work = counted;
}

void OctreeDistanceField::adopt(const std::shared_ptr<VersionedGrid>& grid) {
  version_ = VersionedGrid::take_version(grid);
  squared_ = version_->cells();
  cells_ = grid->cells();
}

std::size_t OctreeDistanceField::memory_bytes() const { return distinct_memory_bytes({this}); }

std::size_t OctreeDistanceField::distinct_memory_bytes(const std::vector<const OctreeDistanceField*>& fields) {
  std::vector<const VersionedGrid*> grids;
  std::vector<const GridVersion*> versions;
  std::size_t bytes = 0;
  for (const OctreeDistanceField* f : fields) {
    if (f == nullptr || !f->version_) continue;
    const GridVersion* v = f->version_.get();
    if (std::find(versions.begin(), versions.end(), v) != versions.end()) continue;
    versions.push_back(v);
    bytes += v->own_bytes();
    const VersionedGrid* g = v->grid().get();
    if (std::find(grids.begin(), grids.end(), g) != grids.end()) continue;
    grids.push_back(g);
    if (g->shares_pages()) bytes += g->bytes();  // (without a file, a version's copy is its own)
  }
  return bytes;
}

bool OctreeDistanceField::same_values(const OctreeDistanceField& other) const {
  return cells_ == other.cells_ && std::equal(squared_, squared_ + cells_, other.squared_) && bound_of_squared_ == other.bound_of_squared_ && resolution_ == other.resolution_ &&
         cap_ == other.cap_ && std::equal(grid_lo_, grid_lo_ + 3, other.grid_lo_) && std::equal(size_, size_ + 3, other.size_);
}

double OctreeDistanceField::lower_bound(const Vec3& p) const {
  if (cells_ == 0 || !p.allFinite()) return 0.0;
  std::int64_t i[3];
  for (int a = 0; a < 3; ++a) {
    i[a] = voxel_at(p[a], inverse_);
    if (i[a] < inner_lo_[a] || i[a] > inner_hi_[a]) return 0.0;
    i[a] -= grid_lo_[a];
  }
  const std::uint32_t squared = squared_[(i[0] * size_[1] + i[1]) * size_[2] + i[2]];
  const double bound = squared < bound_of_squared_.size() ? bound_of_squared_[squared] : cap_;
  // The margin covers p / res rounded across a voxel face and the square root's rounding.
  return std::max(0.0, bound - kVolumeMargin * (1.0 + p.lpNorm<Eigen::Infinity>() + cap_));
}

std::optional<bool> OctreeDistanceField::ball_meets_occupied(const Vec3& centre, double radius) const {
  if (cells_ == 0 || !centre.allFinite() || !std::isfinite(radius)) return std::nullopt;
  std::int64_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    // One voxel more on each side than the ball needs: p / res may round across a face.
    lo[a] = voxel_at(centre[a] - radius, inverse_) - 1 - grid_lo_[a];
    hi[a] = voxel_at(centre[a] + radius, inverse_) + 1 - grid_lo_[a];
    if (lo[a] < 0 || hi[a] >= size_[a]) return std::nullopt;
  }
  // Grown a little: the clamped differences round, and a touching cube must count.
  const double grown = grown_radius(radius) + kVolumeMargin * (1.0 + centre.lpNorm<Eigen::Infinity>());
  const double r2 = grown * grown;
  for (std::int64_t x = lo[0]; x <= hi[0]; ++x) {
    const double cx = centre.x() - std::clamp(centre.x(), double(x + grid_lo_[0]) * resolution_, double(x + grid_lo_[0] + 1) * resolution_);
    if (cx * cx > r2) continue;
    for (std::int64_t y = lo[1]; y <= hi[1]; ++y) {
      const double cy = centre.y() - std::clamp(centre.y(), double(y + grid_lo_[1]) * resolution_, double(y + grid_lo_[1] + 1) * resolution_);
      if (cx * cx + cy * cy > r2) continue;
      const std::uint32_t* row = squared_ + (x * size_[1] + y) * size_[2];
      for (std::int64_t z = lo[2]; z <= hi[2]; ++z) {
        if (row[z] != 0) continue;
        const double cz = centre.z() - std::clamp(centre.z(), double(z + grid_lo_[2]) * resolution_, double(z + grid_lo_[2] + 1) * resolution_);
        if (cx * cx + cy * cy + cz * cz <= r2) return true;
      }
    }
  }
  return false;
}

}  // namespace bvh_collision
