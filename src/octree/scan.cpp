#include "bvh_collision/octree/scan.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/octree/voxel_set.h"

namespace bvh_collision {
namespace {

std::optional<OctreeKey> key_of(const OctreeGrid& grid, const ScanPoint& p) { return grid.key(Vec3(p.cast<double>())); }

// OctoMap's Vector3::norm(): float squares summed in float, square root in double.
double float_norm(const ScanPoint& v) {
  const float squared = v.x() * v.x() + v.y() * v.y() + v.z() * v.z();
  return std::sqrt(static_cast<double>(squared));
}

// Which axis a ray steps along next, as OctoMap decides it (t_max[0] < t_max[1] ? (t_max[0] <
// t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2)), and that axis's crossing moved on, without a
// branch: the axis is as good as random from step to step, and the mispredicted branch cost more
// than the rest of a step (a room's depth image at 5 cm: 12.6 ns a step with the branch and the
// crossings in memory). The masks are all ones for the axis taken, zero for the others.
#if defined(__SSE2__)
struct RayClock {
  __m128d t[3], delta[3];
  void set(const double* t_max, const double* t_delta) {
    for (int i = 0; i < 3; ++i) t[i] = _mm_set_sd(t_max[i]), delta[i] = _mm_set_sd(t_delta[i]);
  }
  // Steps one axis; its choice as 0 / -1 masks in `take`.
  void step(int* take) {
    const __m128d xy = _mm_cmplt_sd(t[0], t[1]), xz = _mm_cmplt_sd(t[0], t[2]), yz = _mm_cmplt_sd(t[1], t[2]);
    const __m128d m0 = _mm_and_pd(xy, xz), m1 = _mm_andnot_pd(xy, yz);
    const __m128d m2 = _mm_andnot_pd(_mm_or_pd(m0, m1), _mm_castsi128_pd(_mm_set1_epi32(-1)));
    t[0] = _mm_add_sd(t[0], _mm_and_pd(m0, delta[0]));
    t[1] = _mm_add_sd(t[1], _mm_and_pd(m1, delta[1]));
    t[2] = _mm_add_sd(t[2], _mm_and_pd(m2, delta[2]));
    take[0] = -(_mm_movemask_pd(m0) & 1), take[1] = -(_mm_movemask_pd(m1) & 1), take[2] = -(_mm_movemask_pd(m2) & 1);
  }
  // OctoMap's std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length.
  bool beyond(double length) const {
    return _mm_comigt_sd(_mm_min_sd(_mm_min_sd(t[0], t[1]), t[2]), _mm_set_sd(length)) != 0;
  }
};
#else
struct RayClock {
  double t[3], delta[3];
  void set(const double* t_max, const double* t_delta) {
    for (int i = 0; i < 3; ++i) t[i] = t_max[i], delta[i] = t_delta[i];
  }
  void step(int* take) {
    const int dim = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
    t[dim] += delta[dim];
    for (int i = 0; i < 3; ++i) take[i] = i == dim ? -1 : 0;
  }
  bool beyond(double length) const { return std::min(std::min(t[0], t[1]), t[2]) > length; }
};
#endif

// One ray's walk as OctoMap's computeRayKeys sets it up: the voxel it is in (16-bit keys as
// ints), the end's, each axis's step and crossings, how many steps it may still take.
struct RayWalk {
  int key[3], end[3], step[3];
  RayClock clock;
  double length;
  int steps_left;
};

enum class RayStart { kOutside, kNoVoxel, kOriginOnly, kWalk };

// kOutside: an end outside the key range; kNoVoxel: both ends in one voxel; kOriginOnly: the
// origin's voxel and no step. Amanatides & Woo's traversal with OctoMap's exact mix of float and
// double arithmetic.
RayStart start_ray(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, RayWalk& w) {
  const auto key_origin = key_of(grid, origin), key_end = key_of(grid, end);
  if (!key_origin || !key_end) return RayStart::kOutside;
  if (*key_origin == *key_end) return RayStart::kNoVoxel;
  for (int i = 0; i < 3; ++i) w.key[i] = key_origin->k[i], w.end[i] = key_end->k[i];
  ScanPoint direction = end - origin;
  const float length = static_cast<float>(float_norm(direction));
  // Ends a denormal distance apart in different voxels: the length underflows to 0 and the
  // direction to infinities and NaN, with which the walk below never ended (found by the
  // point_cloud fuzz target). Such a ray crosses no voxel between its ends.
  if (!(length > 0.0f) || !std::isfinite(length)) return RayStart::kOriginOnly;
  direction /= length;
  if (!direction.allFinite()) return RayStart::kOriginOnly;
  double t_max[3], t_delta[3];
  for (int i = 0; i < 3; ++i) {
    w.step[i] = direction[i] > 0.0f ? 1 : (direction[i] < 0.0f ? -1 : 0);
    if (w.step[i] == 0) {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::max();
      continue;
    }
    double border = grid.center(key_origin->k[i]);
    border += static_cast<float>(w.step[i] * grid.resolution() * 0.5);
    t_max[i] = (border - origin[i]) / direction[i];
    t_delta[i] = grid.resolution() / std::fabs(direction[i]);
  }
  w.clock.set(t_max, t_delta);
  w.length = length;
  // Each step moves one voxel along one axis: the walk needs the keys' Manhattan distance, and
  // rounding that carries it beside the end adds a step or two. The cap makes any other rounding
  // a short ray, never an endless one.
  w.steps_left = 8;
  for (int i = 0; i < 3; ++i) w.steps_left += std::abs(w.end[i] - w.key[i]);
  return RayStart::kWalk;
}

// The rest of a walk whose current voxel was entered (and visited): visit(x, y, z) for each voxel
// it crosses before the end's.
template <class Visit>
void walk_on(RayWalk& w, Visit&& visit) {
  int x = w.key[0], y = w.key[1], z = w.key[2];
  const int end_x = w.end[0], end_y = w.end[1], end_z = w.end[2];
  while (w.steps_left-- > 0) {
    int take[3];
    w.clock.step(take);
    x = (x + (w.step[0] & take[0])) & 0xFFFF;  // a key is 16 bits, as OctoMap's
    y = (y + (w.step[1] & take[1])) & 0xFFFF;
    z = (z + (w.step[2] & take[2])) & 0xFFFF;
    if (((x ^ end_x) | (y ^ end_y) | (z ^ end_z)) == 0) break;
    // Rounding can carry the walk past the end voxel: stop once beyond the ray's length.
    if (w.clock.beyond(w.length)) break;
    visit(x, y, z);
  }
}

// OctoMap's computeRayKeys: visit(x, y, z) (16-bit keys as ints) for every voxel a ray from
// `origin` to `end` crosses, without the end's voxel. False when either end lies outside the key
// range.
template <class Visit>
bool walk_ray(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, Visit&& visit) {
  RayWalk w;
  const RayStart start = start_ray(grid, origin, end, w);
  if (start == RayStart::kOutside) return false;
  if (start == RayStart::kNoVoxel) return true;
  visit(w.key[0], w.key[1], w.key[2]);
  if (start == RayStart::kWalk) walk_on(w, visit);
  return true;
}

// walk_ray marking the voxels in the bitmap's box there, the others by outside(x, y, z). The
// same steps as walk_on, with the voxel followed by its bit's index and, per axis, how many steps
// the walk may still take before it leaves the box (each axis moves one way only: once out, the
// walk stays out, and walk_on takes the rest).
template <class Outside>
bool walk_ray_marking(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, VoxelBitGrid& bits,
                      Outside&& outside) {
  RayWalk w;
  const RayStart start = start_ray(grid, origin, end, w);
  if (start == RayStart::kOutside) return false;
  if (start == RayStart::kNoVoxel) return true;
  std::uint64_t index = 0, end_index = ~std::uint64_t{0};
  if (!bits.index_of(w.key[0], w.key[1], w.key[2], index)) {
    outside(w.key[0], w.key[1], w.key[2]);
    if (start == RayStart::kWalk) walk_on(w, outside);
    return true;
  }
  bits.mark(index);
  if (start != RayStart::kWalk) return true;
  bits.index_of(w.end[0], w.end[1], w.end[2], end_index);  // (none: the end lies outside)
  std::int64_t left[3], stride[3];
  for (int i = 0; i < 3; ++i) {
    left[i] = w.step[i] > 0 ? bits.max(i) - w.key[i] : w.step[i] < 0 ? w.key[i] - bits.min(i) : std::numeric_limits<std::int32_t>::max();
    stride[i] = w.step[i] * static_cast<std::int64_t>(bits.stride(i));
  }
  // (Named one by one: as arrays, the compiler kept them in memory.)
  std::int64_t left_x = left[0], left_y = left[1], left_z = left[2];
  const std::int64_t stride_x = stride[0], stride_y = stride[1], stride_z = stride[2];
  std::uint64_t* const words = bits.words();
  while (w.steps_left-- > 0) {
    int take[3];
    w.clock.step(take);
    const std::int64_t tx = take[0], ty = take[1], tz = take[2];
    left_x += tx, left_y += ty, left_z += tz;
    index += static_cast<std::uint64_t>((stride_x & tx) + (stride_y & ty) + (stride_z & tz));
    if ((left_x | left_y | left_z) < 0) {  // out of the box: the key, then as walk_on
      left[0] = left_x, left[1] = left_y, left[2] = left_z;
      for (int i = 0; i < 3; ++i) {
        if (w.step[i] != 0) w.key[i] = (w.step[i] > 0 ? bits.max(i) - int(left[i]) : bits.min(i) + int(left[i])) & 0xFFFF;
      }
      if (w.key[0] == w.end[0] && w.key[1] == w.end[1] && w.key[2] == w.end[2]) return true;
      if (w.clock.beyond(w.length)) return true;
      outside(w.key[0], w.key[1], w.key[2]);
      walk_on(w, outside);
      return true;
    }
    if (index == end_index) break;
    if (w.clock.beyond(w.length)) break;
    words[index >> 6] |= std::uint64_t{1} << (index & 63);
  }
  return true;
}

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
  if (!walk_ray(grid, origin, p, [&](int x, int y, int z) { part.ray.push_back(key_at(x, y, z)); })) return;
  for (auto it = part.ray.rbegin(); it != part.ray.rend() && box.contains(*it); ++it) part.free_voxel(it->k[0], it->k[1], it->k[2]);
}

// ScanOptions::clip_rays_to_workspace: an end inside the box and within range as OctoMap has it;
// any other ray frees the voxels it crosses inside the box, up to max_range (a box is convex: they
// are one run along the ray).
void cast_clipped(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
                  const ScanOptions& options, const KeyBox& box, ScanPart& part) {
  const bool within = within_range(p, origin, options);
  if (within && options.workspace->contains(p) && mark_end) return cast_in_workspace(grid, p, true, origin, options, box, part);
  ScanPoint end = p;
  if (!within) {
    ScanPoint direction = p - origin;
    direction /= static_cast<float>(float_norm(direction));
    end = origin + direction * static_cast<float>(options.max_range);
  }
  // (The dense box lies inside the workspace's.)
  if (!walk_ray_marking(grid, origin, end, part.dense, [&](int x, int y, int z) {
        if (box.contains(key_at(x, y, z))) part.free.insert(key_at(x, y, z));
      })) {
    ++part.stats.skipped_outside;
  }
}

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
  const bool ray_inside = walk_ray_marking(grid, origin, end, part.dense, [&](int x, int y, int z) { part.free.insert(key_at(x, y, z)); });
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

void cast_all(const OctreeGrid& grid, const ScanRays& rays, std::size_t first, std::size_t last,
              const ScanPoint& origin, const ScanOptions& options, ScanPart& part) {
  std::optional<KeyBox> box;
  if (options.workspace) box = key_box(grid, *options.workspace);
  for (; first != last; ++first) {
    const ScanPoint& p = rays[first];
    if (!p.allFinite()) {
      ++part.stats.skipped_invalid;
    } else if (box && options.clip_rays_to_workspace) {
      cast_clipped(grid, p, rays.marks(first), origin, options, *box, part);
    } else if (box) {
      cast_in_workspace(grid, p, rays.marks(first), origin, options, *box, part);
    } else {
      cast(grid, p, rays.marks(first), origin, options, part);
    }
  }
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
      cast_all(grid, rays, begin, std::min(rays.size(), begin + kBlock), origin, options, parts[t]);
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

bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys) {
  keys.clear();
  return walk_ray(grid, origin, end, [&](int x, int y, int z) { keys.push_back(key_at(x, y, z)); });
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
