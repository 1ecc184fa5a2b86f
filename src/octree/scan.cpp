#include "bvh_collision/octree/scan.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "bvh_collision/geometry/simd_path.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/octree/detail/ray_walk.h"
#include "bvh_collision/octree/voxel_set.h"

namespace bvh_collision {
namespace {

using ray_walk::float_norm;
using ray_walk::key_of;
using ray_walk::walk_ray;
using ray_walk::walk_ray_marking;

OctreeKey key_at(int x, int y, int z) {
  return OctreeKey{{static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), static_cast<std::uint16_t>(z)}};
}

// What one thread gathers from its share of a scan.
// Free voxels go to `dense` when they lie in its box (every voxel the scan's rays can cross,
// when that box is small enough: cast_scan), else to `free`.
struct ScanPart {
  VoxelSet free, occupied;
  VoxelBitGrid dense;
  ScanStats stats;
  std::vector<OctreeKey> ray;  // scratch for the workspace case
  void free_voxel(int x, int y, int z) {
    if (!dense.insert(x, y, z)) free.insert(key_at(x, y, z));
  }
};

struct KeyBox {
  OctreeKey min, max;
  bool contains(const OctreeKey& k) const {
    for (int i = 0; i < 3; ++i) {
      if (k.k[i] < min.k[i] || k.k[i] > max.k[i]) return false;
    }
    return true;
  }
};

KeyBox key_box(const OctreeGrid& grid, const ScanWorkspace& w) {
  KeyBox box;
  for (int i = 0; i < 3; ++i) {
    box.min.k[i] = grid.key(double(w.min[i])).value_or(w.min[i] < 0 ? 0 : 0xFFFF);
    box.max.k[i] = grid.key(double(w.max[i])).value_or(w.max[i] < 0 ? 0 : 0xFFFF);
  }
  return box;
}

bool within_range(const ScanPoint& p, const ScanPoint& origin, const ScanOptions& options) {
  return options.max_range < 0.0 || float_norm(p - origin) <= options.max_range;
}

// OctoMap's bounding-box branch: points outside the box (or beyond max_range) are dropped; a kept
// ray frees its voxels from the end point back to where it leaves the box.
template <class Clock>
void cast_in_workspace(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
                       const ScanOptions& options, const KeyBox& box, ScanPart& part) {
  if (!within_range(p, origin, options) || !options.workspace->contains(p)) {
    ++part.stats.skipped_workspace;
    return;
  }
  if (const auto k = key_of(grid, p)) {
    if (mark_end) part.occupied.insert(*k);
  } else {
    ++part.stats.skipped_outside;
  }
  part.ray.clear();
  if (!walk_ray<Clock>(grid, origin, p, [&](int x, int y, int z) { part.ray.push_back(key_at(x, y, z)); })) return;
  for (auto it = part.ray.rbegin(); it != part.ray.rend() && box.contains(*it); ++it) part.free_voxel(it->k[0], it->k[1], it->k[2]);
}

// ScanOptions::clip_rays_to_workspace: an end inside the box and within range as OctoMap has it;
// any other ray frees the voxels it crosses inside the box, up to max_range (a box is convex: they
// are one run along the ray).
template <class Clock>
void cast_clipped(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
                  const ScanOptions& options, const KeyBox& box, ScanPart& part) {
  const bool within = within_range(p, origin, options);
  if (within && options.workspace->contains(p) && mark_end) return cast_in_workspace<Clock>(grid, p, true, origin, options, box, part);
  ScanPoint end = p;
  if (!within) {
    ScanPoint direction = p - origin;
    direction /= static_cast<float>(float_norm(direction));
    end = origin + direction * static_cast<float>(options.max_range);
  }
  // (The dense box lies inside the workspace's.)
  if (!walk_ray_marking<Clock>(grid, origin, end, part.dense, [&](int x, int y, int z) {
        if (box.contains(key_at(x, y, z))) part.free.insert(key_at(x, y, z));
      })) {
    ++part.stats.skipped_outside;
  }
}

template <class Clock>
void cast(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
          const ScanOptions& options, ScanPart& part) {
  const bool within = within_range(p, origin, options);
  ScanPoint end = p;
  if (!within) {
    // OctoMap shortens the ray to max_range (float arithmetic) and clears along it only.
    ScanPoint direction = p - origin;
    direction /= static_cast<float>(float_norm(direction));
    end = origin + direction * static_cast<float>(options.max_range);
  }
  const bool ray_inside = walk_ray_marking<Clock>(grid, origin, end, part.dense, [&](int x, int y, int z) { part.free.insert(key_at(x, y, z)); });
  if (!within) {
    part.stats.skipped_outside += !ray_inside;
    return;
  }
  if (const auto k = key_of(grid, p)) {
    if (mark_end) part.occupied.insert(*k);
  } else {
    ++part.stats.skipped_outside;  // the end point is outside the key range: nothing inserted
  }
}

// A scan's two lists seen as one sequence: end points that mark, then end points that only clear.
struct ScanRays {
  const std::vector<ScanPoint>& points;
  const std::vector<ScanPoint>& clear_only;
  std::size_t size() const { return points.size() + clear_only.size(); }
  bool marks(std::size_t i) const { return i < points.size(); }
  const ScanPoint& operator[](std::size_t i) const { return marks(i) ? points[i] : clear_only[i - points.size()]; }
};

template <class Clock>
void cast_all_with(const OctreeGrid& grid, const ScanRays& rays, std::size_t first, std::size_t last,
                   const ScanPoint& origin, const ScanOptions& options, ScanPart& part) {
  std::optional<KeyBox> box;
  if (options.workspace) box = key_box(grid, *options.workspace);
  for (; first != last; ++first) {
    const ScanPoint& p = rays[first];
    if (!p.allFinite()) {
      ++part.stats.skipped_invalid;
    } else if (box && options.clip_rays_to_workspace) {
      cast_clipped<Clock>(grid, p, rays.marks(first), origin, options, *box, part);
    } else if (box) {
      cast_in_workspace<Clock>(grid, p, rays.marks(first), origin, options, *box, part);
    } else {
      cast<Clock>(grid, p, rays.marks(first), origin, options, part);
    }
  }
}

// The rays' walks built twice (geometry/simd_path.h), each flattened so that its build holds the
// walk. With AVX2 a step takes about 0.7 of the default build's time (three-operand forms, no
// register copies, one blend a select: a room's depth image at 5 cm, docs/performance.md); no
// fused multiply-add is enabled, so both take the same steps.
__attribute__((flatten)) void cast_all_generic(const OctreeGrid& grid, const ScanRays& rays, std::size_t first,
                                               std::size_t last, const ScanPoint& origin, const ScanOptions& options,
                                               ScanPart& part) {
  cast_all_with<ray_walk::SelectClock>(grid, rays, first, last, origin, options, part);
}

#if defined(__x86_64__) && defined(__SSE2__)
__attribute__((target("avx2"), flatten)) void cast_all_avx2(const OctreeGrid& grid, const ScanRays& rays, std::size_t first,
                                                            std::size_t last, const ScanPoint& origin,
                                                            const ScanOptions& options, ScanPart& part) {
  cast_all_with<ray_walk::BlendClock>(grid, rays, first, last, origin, options, part);
}
#endif

void cast_all(const OctreeGrid& grid, const ScanRays& rays, std::size_t first, std::size_t last, const ScanPoint& origin,
              const ScanOptions& options, SimdPath path, ScanPart& part) {
#if defined(__x86_64__) && defined(__SSE2__)
  if (path == SimdPath::kAvx2) return cast_all_avx2(grid, rays, first, last, origin, options, part);
#endif
  cast_all_generic(grid, rays, first, last, origin, options, part);
}

int thread_count(const ScanOptions& options, std::size_t points) {
  const int wanted = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  // A thread pays for itself only with a few thousand rays to cast.
  return static_cast<int>(std::clamp<std::size_t>(points / 4096, 1, static_cast<std::size_t>(std::max(wanted, 1))));
}

// The box of keys whose crossed voxels a bitmap holds, when one pays: the box of the sensor and
// the end points (a ray shortened to max_range ends on its segment; a walk that rounding carries
// outside goes to the VoxelSet), inside the workspace's box when there is one (only its voxels
// are freed), and within ScanOptions::max_dense_voxels and a few words a ray (a few points far
// apart need no large bitmap).
std::optional<KeyBox> dense_box(const OctreeGrid& grid, const ScanRays& rays, const ScanPoint& origin, const ScanOptions& options) {
  ScanPoint lo = origin, hi = origin;
  std::size_t finite = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const ScanPoint& p = rays[i];
    if (!p.allFinite()) continue;
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
    ++finite;
  }
  const KeyBox box = key_box(grid, ScanWorkspace{lo, hi});
  KeyBox dense = box;
  if (options.workspace) {
    const KeyBox w = key_box(grid, *options.workspace);
    for (int i = 0; i < 3; ++i) {
      dense.min.k[i] = std::max(box.min.k[i], w.min.k[i]);
      dense.max.k[i] = std::min(box.max.k[i], w.max.k[i]);
    }
  }
  // (A bitmap's words should not outnumber the rays' steps many times.)
  const std::uint64_t limit = std::min<std::uint64_t>(options.max_dense_voxels, 64 * (8 * finite + 4096));
  if (limit == 0) return std::nullopt;
  if (VoxelBitGrid::volume(dense.min, dense.max) > limit) {
    // Too large: the cube about the sensor that the limit allows, where every ray starts (a
    // LiDAR's rays are densest near it); the walk leaves the bitmap for the set at its faces.
    const auto half = static_cast<int>((std::cbrt(static_cast<double>(limit)) - 1.0) / 2.0);
    const KeyBox sensor = key_box(grid, ScanWorkspace{origin, origin});
    for (int i = 0; i < 3; ++i) {
      dense.min.k[i] = static_cast<std::uint16_t>(std::max(int{dense.min.k[i]}, sensor.min.k[i] - half));
      dense.max.k[i] = static_cast<std::uint16_t>(std::min(int{dense.max.k[i]}, sensor.max.k[i] + half));
    }
  }
  const std::uint64_t voxels = VoxelBitGrid::volume(dense.min, dense.max);
  if (voxels == 0 || voxels > limit) return std::nullopt;
  return dense;
}

// Cast the scan's rays on several threads, each into its own sets, then merge. Threads take
// blocks of rays as they go: a depth image's far rows have rays many times longer than its near
// rows, so fixed halves would leave one core idle half the time.
ScanPart cast_scan(const OctreeGrid& grid, const ScanRays& rays, const ScanPoint& origin, const ScanOptions& options) {
  const SimdPath path = resolve_simd_path(options.simd, "ScanOptions::simd");
  const auto threads = static_cast<unsigned>(thread_count(options, rays.size()));
  std::vector<ScanPart> parts(threads);
  constexpr std::size_t kBlock = 2048;
  std::atomic<std::size_t> next{0};
  const std::optional<KeyBox> box = dense_box(grid, rays, origin, options);
  // Each participant gathers into its own part; whoever takes part (the caller alone when the
  // pool is busy) takes blocks until none is left.
  ThreadPool::shared().run(threads, [&](unsigned t) {
    if (box) parts[t].dense = VoxelBitGrid(box->min, box->max);
    for (std::size_t begin; (begin = next.fetch_add(kBlock)) < rays.size();) {
      cast_all(grid, rays, begin, std::min(rays.size(), begin + kBlock), origin, options, path, parts[t]);
    }
  });
  ScanPart& all = parts.front();
  VoxelBitGrid* dense = nullptr;  // the participants' bitmaps in one, then into the set
  for (ScanPart& part : parts) {
    if (!part.dense.has_box()) continue;
    if (dense) {
      dense->insert_all(part.dense);
    } else {
      dense = &part.dense;
    }
  }
  if (dense) dense->append_to(all.free);
  all.stats.bitmap = dense != nullptr;
  for (std::size_t t = 1; t < parts.size(); ++t) {
    all.free.insert_all(parts[t].free);
    all.occupied.insert_all(parts[t].occupied);
    all.stats.skipped_invalid += parts[t].stats.skipped_invalid;
    all.stats.skipped_outside += parts[t].stats.skipped_outside;
    all.stats.skipped_workspace += parts[t].stats.skipped_workspace;
  }
  return std::move(all);
}

}  // namespace

namespace {

template <class Clock>
bool walk_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys) {
  return walk_ray<Clock>(grid, origin, end, [&](int x, int y, int z) { keys.push_back(key_at(x, y, z)); });
}

#if defined(__x86_64__) && defined(__SSE2__)
__attribute__((target("avx2"), flatten)) bool walk_keys_avx2(const OctreeGrid& grid, const ScanPoint& origin,
                                                             const ScanPoint& end, std::vector<OctreeKey>& keys) {
  return walk_keys<ray_walk::BlendClock>(grid, origin, end, keys);
}
#endif

}  // namespace

bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys,
              SimdPath path) {
  keys.clear();
#if defined(__x86_64__) && defined(__SSE2__)
  if (resolve_simd_path(path, "ray_keys") == SimdPath::kAvx2) return walk_keys_avx2(grid, origin, end, keys);
#else
  resolve_simd_path(path, "ray_keys");
#endif
  return walk_keys<ray_walk::SelectClock>(grid, origin, end, keys);
}

ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const ScanPoint& origin,
                      const ScanOptions& options) {
  return insert_scan(tree, points, {}, origin, options);
}

ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const std::vector<ScanPoint>& clear_only,
                      const ScanPoint& origin, const ScanOptions& options) {
  check_limit("a scan with its points", double(points.size()) + double(clear_only.size()), options.limits.cloud_points,
              "max_cloud_points");
  if (options.max_range > 0.0) {
    check_limit("a ray of max_range " + std::to_string(options.max_range) + " m at resolution " +
                    std::to_string(tree.resolution()) + " m with its voxels",
                std::ceil(options.max_range / tree.resolution()), options.limits.ray_voxels, "max_ray_voxels");
  }
  const ScanRays rays{points, clear_only};
  ScanPart scan = cast_scan(tree.grid(), rays, origin, options);
  scan.stats.points = rays.size();
  // A voxel that ends a ray is occupied, not also freed. Free updates go first, as in OctoMap.
  scan.free.erase_all(scan.occupied);
  const std::vector<OctreeKey> free = scan.free.sorted_keys(), occupied = scan.occupied.sorted_keys();
  // (The two lists are disjoint: a voxel flips at most once.)
  tree.update_sorted(free, false, &scan.stats.flipped);
  tree.update_sorted(occupied, true, &scan.stats.flipped);
  scan.stats.free = free.size();
  scan.stats.occupied = occupied.size();
  return scan.stats;
}

ScanStats insert_points(Octree& tree, const std::vector<ScanPoint>& points, const ScanOptions& options) {
  ScanStats stats;
  stats.points = points.size();
  VoxelSet occupied;
  for (const ScanPoint& p : points) {
    if (!p.allFinite()) {
      ++stats.skipped_invalid;
    } else if (options.workspace && !options.workspace->contains(p)) {
      ++stats.skipped_workspace;
    } else if (const auto k = key_of(tree.grid(), p)) {
      occupied.insert(*k);
    } else {
      ++stats.skipped_outside;
    }
  }
  const std::vector<OctreeKey> keys = occupied.sorted_keys();
  tree.update_sorted(keys, true, &stats.flipped);
  stats.occupied = keys.size();
  return stats;
}

bool PinholeCamera::valid() const {
  return std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) && std::isfinite(cy) && fx != 0.0 && fy != 0.0;
}

namespace {

// The least-squares line t = a * s + b through the pairs (s, t).
struct LineFit {
  double n = 0, s = 0, t = 0, ss = 0, st = 0;
  void add(double x, double y) { n += 1, s += x, t += y, ss += x * x, st += x * y; }
  bool spread() const { return n >= 2 && ss * n - s * s > 0.5; }  // at least two distinct pixel indices
  double slope() const { return (st * n - s * t) / (ss * n - s * s); }
  double intercept() const { return (t - slope() * s) / n; }
};

bool in_front(const ScanPoint& p) { return p.allFinite() && p.z() > 0.0f; }

}  // namespace

std::optional<PinholeCamera> fit_pinhole(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height) {
  if (organized.size() != width * height) return std::nullopt;
  LineFit across, down;  // x / z against the column, y / z against the row
  for (std::size_t v = 0; v < height; ++v) {
    for (std::size_t u = 0; u < width; ++u) {
      const ScanPoint& p = organized[v * width + u];
      if (!in_front(p)) continue;
      across.add(double(u), double(p.x()) / p.z());
      down.add(double(v), double(p.y()) / p.z());
    }
  }
  if (!across.spread() || !down.spread()) return std::nullopt;
  const double ax = across.slope(), bx = across.intercept(), ay = down.slope(), by = down.intercept();
  const PinholeCamera camera{1.0 / ax, 1.0 / ay, -bx / ax, -by / ay};
  if (!camera.valid() || !pinhole_agrees(organized, width, height, camera)) return std::nullopt;
  return camera;
}

bool pinhole_agrees(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height,
                    const PinholeCamera& camera) {
  if (organized.size() != width * height || !camera.valid()) return false;
  for (std::size_t v = 0; v < height; ++v) {
    for (std::size_t u = 0; u < width; ++u) {
      const ScanPoint& p = organized[v * width + u];
      if (!p.allFinite() || p.isZero()) continue;  // no return (some drivers write zeros)
      if (!in_front(p)) return false;              // a pinhole camera sees nothing behind it
      const double off_x = double(p.x()) / p.z() - (double(u) - camera.cx) / camera.fx;
      const double off_y = double(p.y()) / p.z() - (double(v) - camera.cy) / camera.fy;
      if (!(std::abs(off_x) <= 1e-3 && std::abs(off_y) <= 1e-3)) return false;
    }
  }
  return true;
}

std::vector<ScanPoint> no_return_ends(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height,
                                      const PinholeCamera& camera, double range) {
  if (organized.size() != width * height) {
    throw std::invalid_argument("no-return rays: the scan has " + std::to_string(organized.size()) + " points, not " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  if (!camera.valid()) throw std::invalid_argument("no-return rays: the camera model is not valid (fx, fy non-zero, all finite)");
  if (!(range > 0.0) || !std::isfinite(range)) throw std::invalid_argument("no-return rays: the range must be positive and finite");
  std::vector<ScanPoint> ends;
  for (std::size_t v = 0; v < height; ++v) {
    for (std::size_t u = 0; u < width; ++u) {
      if (organized[v * width + u].allFinite()) continue;
      const Eigen::Vector3d ray((double(u) - camera.cx) / camera.fx, (double(v) - camera.cy) / camera.fy, 1.0);
      const ScanPoint end = (ray.normalized() * range).cast<float>();
      if (end.allFinite()) ends.push_back(end);  // (a focal length of 1e-300 px has no direction to give)
    }
  }
  return ends;
}

}  // namespace bvh_collision
