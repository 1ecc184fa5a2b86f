// bench_planning's call log and its replay: every state and motion call our rows make, written
// in order (BENCH_PLANNING_LOG), and asked again of a fresh checker on the same problems
// (BENCH_PLANNING_REPLAY), so that two builds are compared on the same calls (a changed answer
// would change the plan, and every later call with it). docs/performance.md shows how.
#pragma once

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/world/environment.h"

namespace bvh_collision {
class SceneChecker;

namespace bench {

// One line a call, "<problem> <row> S <state>" or "<problem> <row> M <earliest> <start> <goal>",
// full states at 17 digits.
struct CallLog {
  std::FILE* file = nullptr;
  int problem = 0, row = 0;
  void state(const std::vector<double>& q) const;
  void motion(const std::vector<double>& a, const std::vector<double>& b, bool earliest) const;
};

struct LoggedCall {
  bool motion = false, earliest = false;
  std::vector<double> a, b;
};
// Per problem and row, the calls in the order the planner made them.
using LoggedCalls = std::map<std::pair<int, int>, std::vector<LoggedCall>>;
LoggedCalls read_call_log(const char* path, std::size_t variables);

struct ReplayCount {
  std::size_t states = 0, free_states = 0, motions = 0, free_motions = 0, intervals = 0;
  double fractions = 0.0;  // the sum of the colliding motions' last valid fractions
  double seconds = 0.0;    // per problem the fastest of BENCH_PLANNING_REPLAY_REPEAT replays, summed
};

// Problem k's calls of one row (0: tolerance 0, 1: 10 mm) asked of a checker built as the
// planning context builds it; BENCH_PLANNING_PAIR_GROWTH fixes the self pairs' exact growth, which
// the checker times at load (callgrind's slowdown may choose another).
void replay_problem(const CollisionChecker& checker, const std::shared_ptr<const Environment>& env, const LoggedCalls& calls,
                    int k, int row, ReplayCount& count);
void print_replay(const std::string& robot, const std::string& row, const CollisionChecker& checker, const ReplayCount& count);

}  // namespace bench
}  // namespace bvh_collision
