// SceneChecker's memory of free states, answered motions and free segments (scene_memory.h).
#include "scene_memory.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace bvh_collision {

using scene_memory::FreeSegments;
using scene_memory::FreeStates;
using scene_memory::KnownMotions;

namespace {

std::uint64_t hash_of(const double* values, std::size_t n, std::uint64_t h = 0x9E3779B97F4A7C15ULL) {
  for (std::size_t j = 0; j < n; ++j) {
    std::uint64_t bits;
    std::memcpy(&bits, values + j, sizeof bits);
    h = (h ^ bits) * 0xBF58476D1CE4E5B9ULL;
    h ^= h >> 31;
  }
  return h;
}

std::size_t slot_of(const double* state, std::size_t n) { return static_cast<std::size_t>(hash_of(state, n) % FreeStates::kSlots); }

std::size_t slot_of(const double* start, const double* goal, std::size_t n, bool earliest) {
  const std::uint64_t h = hash_of(goal, n, hash_of(start, n) ^ (earliest ? 0x5851F42D4C957F2DULL : 0));
  return static_cast<std::size_t>(h % KnownMotions::kSlots);
}

// Within this of the segment, variable by variable (radians or metres), a state counts as on it:
// a hundred times the rounding of a planner's interpolation between two of its states.
constexpr double kOnSegment = 1e-13;

// Does `state` lie on the segment (start, delta): each of its values within kOnSegment of the
// segment's at one fraction in [0, 1] (found from the variable that changes most)? When it does
// and `offset` is given, each difference (with the rounding of computing it) raises its variable's
// entry there.
// The variables are taken from `longest` on (a planning group's are mostly next to each other,
// and a state off the segment differs in those: the variables before it, outside the group, all
// agree).
bool on_segment(const double* start, const double* delta, int longest, const double* state, std::size_t n, double* offset) {
  const double t = std::clamp((state[longest] - start[longest]) / delta[longest], 0.0, 1.0);
  for (std::size_t i = 0, j = static_cast<std::size_t>(longest); i < n; ++i, j = j + 1 == n ? 0 : j + 1) {
    const double d = std::abs(start[j] + t * delta[j] - state[j]);
    if (!(d <= kOnSegment)) return false;
    // (The product, the sums and delta's own rounding: a few units of 1.1e-16 of these values.)
    if (offset != nullptr) offset[j] = std::max(offset[j], d + 1e-15 * (1.0 + std::abs(start[j]) + std::abs(delta[j]) + std::abs(state[j])));
  }
  return true;
}

// A first test of a slot: true whenever on_segment(state) is, with no division and no row read (a
// planner's motion that no slot holds scans all 128 slots, three scans a motion: with a division
// a slot, the scans took 5 % of the replayed planner calls' time). on_segment's fraction t puts
// the longest variable x within kOnSegment of the segment's at t, so inside its range padded by
// kOnSegment, and the second, y, within kOnSegment of b + t e (start b, change e), where
// t = (x - a) / d up to kOnSegment / |d| (clamped only within kOnSegment of an end). So
// |(x - a) e/d + b - y| <= 2 kOnSegment (|e/d| <= 1), plus the rounding of these few operations, a
// few units of 1.1e-16 of the values: `slack` (1e-11 and 1e-14 of the values' sizes,
// remember_free_motion) holds both with a wide margin; a slot it lets through is then decided by
// on_segment.
inline bool near_segment(const FreeSegments& f, std::size_t k, const double* state) {
  const double x = state[f.longest[k]];
  if (!(x >= f.low[k] && x <= f.high[k])) return false;
  return std::abs((x - f.start_longest[k]) * f.ratio[k] + (f.start_second[k] - state[f.second[k]])) <= f.slack[k];
}

}  // namespace

std::size_t SceneChecker::state_slot(const double* state) const { return slot_of(state, checker_.model().variable_count()); }

[[gnu::noinline]] SceneChecker::StateScratch& SceneChecker::state_scratch() {
  thread_local StateScratch s;
  return s;
}

bool SceneChecker::known_free(const double* state) const {
  return known_free(state_scratch(), state, slot_of(state, checker_.model().variable_count()));
}

bool SceneChecker::known_free(const StateScratch& scratch, const double* state, std::size_t slot) const {
  const FreeStates& f = scratch.free;
  const std::size_t n = f.n;
  return n == checker_.model().variable_count() && f.serial[slot] == serial_ &&
         std::memcmp(f.values.data() + slot * n, state, n * sizeof(double)) == 0;
}

void SceneChecker::remember_free(const double* state) const {
  remember_free(state_scratch(), state, slot_of(state, checker_.model().variable_count()));
}

void SceneChecker::remember_free(StateScratch& scratch, const double* state, std::size_t slot) const {
  FreeStates& f = scratch.free;
  const std::size_t n = checker_.model().variable_count();
  if (f.n != n) {
    f.n = n;
    f.values.assign(FreeStates::kSlots * n, 0.0);
    f.serial.fill(0);
  }
  f.serial[slot] = serial_;
  std::memcpy(f.values.data() + slot * n, state, n * sizeof(double));
}

bool SceneChecker::known_motion(const double* start, const double* goal, bool earliest, MotionResult& result) const {
  const KnownMotions& k = state_scratch().motions;
  const std::size_t n = k.n;
  if (n != checker_.model().variable_count()) return false;
  const std::size_t slot = slot_of(start, goal, n, earliest);
  const double* ends = k.ends.data() + slot * 2 * n;
  if (k.serial[slot] != serial_ || k.earliest[slot] != earliest || std::memcmp(ends, start, n * sizeof(double)) != 0 ||
      std::memcmp(ends + n, goal, n * sizeof(double)) != 0) {
    return false;
  }
  result = k.result[slot];
  result.states_checked = 0;  // none checked by this call
  return true;
}

void SceneChecker::remember_motion(const double* start, const double* goal, bool earliest, const MotionResult& result) const {
  KnownMotions& k = state_scratch().motions;
  const std::size_t n = checker_.model().variable_count();
  if (k.n != n) {
    k.n = n;
    k.ends.assign(KnownMotions::kSlots * 2 * n, 0.0);
    k.serial.fill(0);
  }
  const std::size_t slot = slot_of(start, goal, n, earliest);
  k.serial[slot] = serial_;
  k.earliest[slot] = earliest;
  k.result[slot] = result;
  std::memcpy(k.ends.data() + slot * 2 * n, start, n * sizeof(double));
  std::memcpy(k.ends.data() + slot * 2 * n + n, goal, n * sizeof(double));
}

// A motion within a segment certified free is free: each of its states lies within the ends'
// offsets from a state of the segment (along the motion the offset interpolates the ends'), and
// over such an offset no point of any link moves farther than kSegmentDisplacement (the links'
// speed bounds, CollisionChecker::link_speed, over the largest offset of each variable). That is a
// thousandth of kPoseMargin, the margin every certified interval's growth carries above rounding
// errors of about 1e-14 m (geometry/safety_margin.h): the certificate covers it.
bool SceneChecker::within_free_motion(const double* start, const double* goal) const {
  StateScratch& scratch = state_scratch();
  FreeSegments& f = scratch.segments;
  const std::size_t n = checker_.model().variable_count();
  if (f.n != n) return false;
  for (std::size_t k = 0; k < FreeSegments::kSlots; ++k) {
    const double* from = f.rows.data() + k * 2 * n;
    if (f.serial[k] != serial_ || !near_segment(f, k, start) || !near_segment(f, k, goal) ||
        !on_segment(from, from + n, f.longest[k], start, n, nullptr) || !on_segment(from, from + n, f.longest[k], goal, n, nullptr)) {
      continue;
    }
    // The largest offset per variable, from the value of either end farthest from zero (a slide
    // beyond its travel lengthens the levers above it by the most there: CollisionChecker::link_speed).
    std::vector<double>& offset = scratch.offset;
    std::vector<double>& far = scratch.far_end;
    std::vector<double>& shifted = scratch.shifted;
    offset.assign(n, 0.0);
    on_segment(from, from + n, f.longest[k], start, n, offset.data());
    on_segment(from, from + n, f.longest[k], goal, n, offset.data());
    far.resize(n);
    shifted.resize(n);
    for (std::size_t j = 0; j < n; ++j) {
      far[j] = std::abs(start[j]) >= std::abs(goal[j]) ? start[j] : goal[j];
      shifted[j] = far[j] + (far[j] >= 0.0 ? offset[j] : -offset[j]);
    }
    if (!std::all_of(links_.begin(), links_.end(), [&](int l) { return checker_.link_speed(l, far.data(), shifted.data()) <= kSegmentDisplacement; })) {
      return false;
    }
    f.used[k] = ++f.clock;
    return true;
  }
  return false;
}

void SceneChecker::remember_free_motion(const double* start, const double* goal) const {
  FreeSegments& f = state_scratch().segments;
  const std::size_t n = checker_.model().variable_count();
  int longest = 0;
  for (std::size_t j = 0; j < n; ++j) {
    if (std::abs(goal[j] - start[j]) > std::abs(goal[longest] - start[longest])) longest = static_cast<int>(j);
  }
  if (!(std::abs(goal[longest] - start[longest]) > 0.0)) return;  // a motion that does not move (KnownMotions has it)
  int second = longest;
  for (std::size_t j = 0; j < n; ++j) {
    if (static_cast<int>(j) != longest && (second == longest || std::abs(goal[j] - start[j]) > std::abs(goal[second] - start[second]))) {
      second = static_cast<int>(j);
    }
  }
  if (f.n != n) {
    f.n = n;
    f.rows.assign(FreeSegments::kSlots * 2 * n, 0.0);
    f.serial.fill(0);
    f.used.fill(0);
  }
  const std::size_t k = static_cast<std::size_t>(std::min_element(f.used.begin(), f.used.end()) - f.used.begin());
  double* row = f.rows.data() + k * 2 * n;
  for (std::size_t j = 0; j < n; ++j) row[j] = start[j], row[n + j] = goal[j] - start[j];
  f.serial[k] = serial_;
  f.longest[k] = longest;
  f.second[k] = second;
  const double a = start[longest], d = goal[longest] - start[longest], b = start[second], e = goal[second] - start[second];
  const double size = (std::abs(a) + std::abs(d)) + (std::abs(b) + std::abs(e));
  f.slack[k] = 1e-11 + 1e-14 * size;
  f.low[k] = std::min(a, a + d) - f.slack[k];
  f.high[k] = std::max(a, a + d) + f.slack[k];
  f.start_longest[k] = a;
  f.start_second[k] = b;
  f.ratio[k] = e / d;
  f.used[k] = ++f.clock;
}

}  // namespace bvh_collision
