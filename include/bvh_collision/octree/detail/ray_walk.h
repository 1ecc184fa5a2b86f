// The ray walk of a scan (octree/scan.h's insert_scan, ray_keys): OctoMap's computeRayKeys, step
// for step, visiting each crossed voxel or marking it in a bitmap of the scan's box. Templates on
// the clock that chooses each step's axis, so that one source builds the default walk and the one
// scan.cpp builds for AVX2 (geometry/simd_path.h). Private to the octree layer's sources.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "bvh_collision/octree/scan.h"
#include "bvh_collision/octree/voxel_set.h"

namespace bvh_collision::ray_walk {

inline std::optional<OctreeKey> key_of(const OctreeGrid& grid, const ScanPoint& p) { return grid.key(Vec3(p.cast<double>())); }

// OctoMap's Vector3::norm(): float squares summed in float, square root in double.
inline double float_norm(const ScanPoint& v) {
  const float squared = v.x() * v.x() + v.y() * v.y() + v.z() * v.z();
  return std::sqrt(static_cast<double>(squared));
}

// Which axis a ray steps along next, as OctoMap decides it (t_max[0] < t_max[1] ? (t_max[0] <
// t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2)), and that axis's crossing moved on, without a
// branch: the axis is as good as random from step to step, and the mispredicted branch cost more
// than the rest of a step (a room's depth image at 5 cm: 12.6 ns a step with the branch and the
// crossings in memory). OctoMap's choice is the smallest crossing, ties to the higher axis, so
// each axis's mask is two comparisons (x: tx < ty and tx < tz; y: ty <= tx and ty < tz; z: tz <= tx
// and tz <= ty) and the crossings are never NaN (finite starts, positive deltas): exactly one is
// set. The next crossings are summed before the choice is known and the chosen one selected, so
// a step's chain of dependent instructions is a compare, an and and a select, not also an add.
// step() returns the axis taken as a code: 1 x, 2 y, 0 z (a bit each for x and y). Both lanes of
// a register hold the same crossing.
//
// Two clocks with the same arithmetic, hence the same steps: SelectClock in SSE2 intrinsics for
// the default build (a select is an and, an and-not and an or), BlendClock in GCC's vector types
// for code built for AVX2, where the compiler makes each select one blend (GCC's SSE2 lowering
// of the vector types moves every lane through a general register: slower than SelectClock).
#if defined(__SSE2__)
struct SelectClock {
  __m128d t[3], delta[3];
  void set(const double* t_max, const double* t_delta) {
    for (int i = 0; i < 3; ++i) t[i] = _mm_set1_pd(t_max[i]), delta[i] = _mm_set1_pd(t_delta[i]);
  }
  static __m128d select(__m128d mask, __m128d yes, __m128d no) { return _mm_or_pd(_mm_and_pd(mask, yes), _mm_andnot_pd(mask, no)); }
  int step() {
    const __m128d next0 = _mm_add_pd(t[0], delta[0]), next1 = _mm_add_pd(t[1], delta[1]), next2 = _mm_add_pd(t[2], delta[2]);
    const __m128d xy = _mm_cmplt_pd(t[0], t[1]), xz = _mm_cmplt_pd(t[0], t[2]), yz = _mm_cmplt_pd(t[1], t[2]);
    const __m128d zy = _mm_cmpnlt_pd(t[1], t[2]);
    const __m128d m0 = _mm_and_pd(xy, xz), m1 = _mm_andnot_pd(xy, yz), m2 = _mm_andnot_pd(xz, zy);
    t[0] = select(m0, next0, t[0]);
    t[1] = select(m1, next1, t[1]);
    t[2] = select(m2, next2, t[2]);
    return _mm_movemask_pd(_mm_unpacklo_pd(m0, m1));
  }
  // OctoMap's std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length.
  bool beyond(double length) const {
    return _mm_comigt_sd(_mm_min_sd(_mm_min_sd(t[0], t[1]), t[2]), _mm_set_sd(length)) != 0;
  }
};

struct BlendClock {
  using Lanes = double __attribute__((vector_size(16)));
  using Masks = std::int64_t __attribute__((vector_size(16)));
  Lanes t[3], delta[3];
  void set(const double* t_max, const double* t_delta) {
    for (int i = 0; i < 3; ++i) t[i] = Lanes{t_max[i], t_max[i]}, delta[i] = Lanes{t_delta[i], t_delta[i]};
  }
  static Lanes select(Masks mask, Lanes yes, Lanes no) { return Lanes((mask & Masks(yes)) | (~mask & Masks(no))); }
  int step() {
    const Lanes next0 = t[0] + delta[0], next1 = t[1] + delta[1], next2 = t[2] + delta[2];
    const Masks xy = t[0] < t[1], xz = t[0] < t[2], yz = t[1] < t[2], zy = t[1] >= t[2];
    const Masks m0 = xy & xz, m1 = ~xy & yz, m2 = ~xz & zy;
    t[0] = select(m0, next0, t[0]);
    t[1] = select(m1, next1, t[1]);
    t[2] = select(m2, next2, t[2]);
    return _mm_movemask_pd(_mm_unpacklo_pd(__m128d(m0), __m128d(m1)));
  }
  bool beyond(double length) const {
    return _mm_comigt_sd(_mm_min_sd(_mm_min_sd(__m128d(t[0]), __m128d(t[1])), __m128d(t[2])), _mm_set_sd(length)) != 0;
  }
};
#else
struct SelectClock {
  double t[3], delta[3];
  void set(const double* t_max, const double* t_delta) {
    for (int i = 0; i < 3; ++i) t[i] = t_max[i], delta[i] = t_delta[i];
  }
  int step() {
    const int dim = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
    t[dim] += delta[dim];
    return (dim + 1) % 3;
  }
  bool beyond(double length) const { return std::min(std::min(t[0], t[1]), t[2]) > length; }
};
#endif

// One ray's walk as OctoMap's computeRayKeys sets it up: the voxel it is in (16-bit keys as
// ints), the end's, each axis's step and crossings, how many steps it may still take.
template <class Clock>
struct RayWalk {
  int key[3], end[3], step[3];
  Clock clock;
  double length;
  int steps_left;
};

enum class RayStart { kOutside, kNoVoxel, kOriginOnly, kWalk };

// kOutside: an end outside the key range; kNoVoxel: both ends in one voxel; kOriginOnly: the
// origin's voxel and no step. Amanatides & Woo's traversal with OctoMap's exact mix of float and
// double arithmetic.
template <class Clock>
RayStart start_ray(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, RayWalk<Clock>& w) {
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
template <class Clock, class Visit>
void walk_on(RayWalk<Clock>& w, Visit&& visit) {
  int x = w.key[0], y = w.key[1], z = w.key[2];
  const int end_x = w.end[0], end_y = w.end[1], end_z = w.end[2];
  // Each key's move by the step's code (Clock::step).
  const int move_x[3] = {0, w.step[0], 0}, move_y[3] = {0, 0, w.step[1]}, move_z[3] = {w.step[2], 0, 0};
  while (w.steps_left-- > 0) {
    const int code = w.clock.step();
    x = (x + move_x[code]) & 0xFFFF;  // a key is 16 bits, as OctoMap's
    y = (y + move_y[code]) & 0xFFFF;
    z = (z + move_z[code]) & 0xFFFF;
    if (((x ^ end_x) | (y ^ end_y) | (z ^ end_z)) == 0) break;
    // Rounding can carry the walk past the end voxel: stop once beyond the ray's length.
    if (w.clock.beyond(w.length)) break;
    visit(x, y, z);
  }
}

// OctoMap's computeRayKeys: visit(x, y, z) (16-bit keys as ints) for every voxel a ray from
// `origin` to `end` crosses, without the end's voxel. False when either end lies outside the key
// range.
template <class Clock, class Visit>
bool walk_ray(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, Visit&& visit) {
  RayWalk<Clock> w;
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
template <class Clock, class Outside>
bool walk_ray_marking(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, VoxelBitGrid& bits,
                      Outside&& outside) {
  RayWalk<Clock> w;
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
  // The steps each axis may still take inside the box, three 21-bit fields of one word, each
  // biased by 2^20: a field that goes below zero clears its bias bit (kInBox). A step's code picks
  // the field to count down and the bit index's move from two small tables.
  constexpr int kField = 21;
  constexpr std::uint64_t kBias = std::uint64_t{1} << (kField - 1);
  constexpr std::uint64_t kInBox = kBias | kBias << kField | kBias << 2 * kField;
  std::uint64_t left = 0, count_down[3] = {};
  std::int64_t move[3] = {};
  for (int i = 0; i < 3; ++i) {
    const int steps = w.step[i] > 0 ? bits.max(i) - w.key[i] : w.step[i] < 0 ? w.key[i] - bits.min(i) : 0xFFFF;
    left |= (kBias + static_cast<std::uint64_t>(steps)) << kField * i;
    const int code = (i + 1) % 3;  // Clock::step's code of axis i
    count_down[code] = std::uint64_t{1} << kField * i;
    move[code] = w.step[i] * static_cast<std::int64_t>(bits.stride(i));
  }
  std::uint64_t* const words = bits.words();
  while (w.steps_left-- > 0) {
    const int code = w.clock.step();
    left -= count_down[code];
    index += static_cast<std::uint64_t>(move[code]);
    if ((left & kInBox) != kInBox) {  // out of the box: the key, then as walk_on
      for (int i = 0; i < 3; ++i) {
        const int steps = static_cast<int>((left >> kField * i) & ((kBias << 1) - 1)) - static_cast<int>(kBias);
        if (w.step[i] != 0) w.key[i] = (w.step[i] > 0 ? bits.max(i) - steps : bits.min(i) + steps) & 0xFFFF;
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

}  // namespace bvh_collision::ray_walk
