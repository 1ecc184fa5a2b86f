// SceneChecker's memory, one per thread (scene_memory.cpp): the states it found free, the motions
// it answered and the motions it certified free, each answering only for the checker (serial)
// that put it there. Private to src/checker (SceneChecker's files).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "bvh_collision/query/scene_checker.h"

namespace bvh_collision {
namespace scene_memory {

// The states a thread last found free, one slot per hash of their values: a planner asks for the
// same state again and again (OMPL's RRTConnect checks a state, then the motion from it; each
// motion starts at a tree node that was the end of an earlier one). A slot answers only for the
// same checker and a state equal bit for bit, so it gives the answer the check would give.
struct FreeStates {
  static constexpr std::size_t kSlots = 64;
  std::array<std::uint64_t, kSlots> serial{};  // 0: empty
  std::vector<double> values;                  // kSlots rows of n values
  std::size_t n = 0;
};

// The motions a thread last answered, one slot per hash of their ends and kind (boolean or
// earliest): OMPL's path simplifier asks again for motions it asked before (reduceVertices draws
// the same pairs of vertices in each of its passes; checkAndRepair checks again every segment of
// the path it made). Like FreeStates, a slot answers only for the same checker and the same ends
// bit for bit, with the answer the check gave. On the planning benchmark's 21,334 motions of its
// 10 mm planner, 3,295 were asked before, 22 % of their time; 256 slots answer 3,106 of them.
struct KnownMotions {
  static constexpr std::size_t kSlots = 256;
  std::array<std::uint64_t, kSlots> serial{};  // 0: empty
  std::array<bool, kSlots> earliest{};
  std::array<MotionResult, kSlots> result{};
  std::vector<double> ends;  // kSlots rows of 2n values: the start, then the goal
  std::size_t n = 0;
};

// The free motions a thread last certified, as segments (start, goal - start), the least recently
// used replaced: OMPL's path simplifier asks for motions between states it put on segments found
// free before (smoothBSpline subdivides the path and checks the new pieces; the path's check after
// each pass), which lie within those segments. On the planning benchmark's 10 mm planner, 5,978
// of 17,829 simplifier motions (22 % of their intervals) lie within an earlier free motion of the
// same problem; 128 slots find all but 2 of them (64: 4,923).
struct FreeSegments {
  static constexpr std::size_t kSlots = 128;
  std::array<std::uint64_t, kSlots> serial{};  // 0: empty
  std::array<std::uint64_t, kSlots> used{};    // when last found or stored (clock)
  std::array<int, kSlots> longest{};           // the variable that changes most along it
  std::array<int, kSlots> second{};            // the one that changes next most (the longest again with one variable)
  std::vector<double> rows;                    // kSlots rows of 2n values: the start, then goal - start
  // A scan's first test, per slot, with no division and no row read (within_free_motion): the
  // longest variable's range, padded by `slack`; the second's start and its change per unit of the
  // longest's.
  std::array<double, kSlots> low{}, high{}, start_longest{}, start_second{}, ratio{}, slack{};
  std::uint64_t clock = 0;
  std::size_t n = 0;
};

}  // namespace scene_memory

// A thread's memory for state checks: the free states, and the posed state (one thread_local
// reached once a check, not at every use: in a shared library each use after a call costs a call
// to __tls_get_addr).
struct SceneChecker::StateScratch {
  scene_memory::FreeStates free;
  scene_memory::KnownMotions motions;
  scene_memory::FreeSegments segments;
  std::vector<double> offset, far_end, shifted;  // within_free_motion's
  Posed posed;
};

}  // namespace bvh_collision
