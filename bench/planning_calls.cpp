#include "planning_calls.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "bvh_collision/query/scene_checker.h"

namespace bvh_collision::bench {

namespace {

void write_values(std::FILE* file, const std::vector<double>& q) {
  for (const double v : q) std::fprintf(file, " %.17g", v);
}

// The logged calls asked again of one checker, in order (callgrind: --toggle-collect=*replay_calls*).
[[gnu::noinline]] void replay_calls(const SceneChecker& scene, const std::vector<LoggedCall>& calls, ReplayCount& count) {
  for (const LoggedCall& c : calls) {
    if (!c.motion) {
      ++count.states;
      count.free_states += !scene.collides(c.a.data());
      continue;
    }
    const MotionResult r = scene.check_motion(c.a.data(), c.b.data(), c.earliest);
    ++count.motions;
    count.free_motions += r.valid;
    count.intervals += r.states_checked;
    if (!r.valid) count.fractions += r.last_valid_fraction;
  }
}

}  // namespace

void CallLog::state(const std::vector<double>& q) const {
  std::fprintf(file, "%d %d S", problem, row);
  write_values(file, q);
  std::fputc('\n', file);
}

void CallLog::motion(const std::vector<double>& a, const std::vector<double>& b, bool earliest) const {
  std::fprintf(file, "%d %d M %d", problem, row, earliest ? 1 : 0);
  write_values(file, a);
  write_values(file, b);
  std::fputc('\n', file);
}

LoggedCalls read_call_log(const char* path, std::size_t variables) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(std::string("cannot read ") + path);
  LoggedCalls calls;
  int problem = 0, row = 0;
  char kind = 0;
  while (in >> problem >> row >> kind) {
    LoggedCall c;
    c.motion = kind == 'M';
    if (c.motion) {
      int earliest = 0;
      in >> earliest;
      c.earliest = earliest != 0;
    }
    for (auto* q : c.motion ? std::vector<std::vector<double>*>{&c.a, &c.b} : std::vector<std::vector<double>*>{&c.a}) {
      q->resize(variables);
      for (double& v : *q) in >> v;
    }
    if (!in) throw std::runtime_error(std::string("malformed call log ") + path);
    calls[{problem, row}].push_back(std::move(c));
  }
  return calls;
}

void replay_problem(const CollisionChecker& checker, const std::shared_ptr<const Environment>& env, const LoggedCalls& calls,
                    int k, int row, ReplayCount& count) {
  SceneCheckOptions options;
  options.tolerance = row == 0 ? 0.0 : 0.01;
  if (const char* growth = std::getenv("BENCH_PLANNING_PAIR_GROWTH")) options.pair_exact_growth = std::atof(growth);
  const auto found = calls.find({k, row});
  if (found == calls.end()) return;
  // BENCH_PLANNING_REPLAY_REPEAT=n asks the calls n times, each of a new checker (whose serial no
  // thread memory holds), and counts the fastest: a time to compare two builds on, beside
  // callgrind's instructions (which miss divisions' latency and cache misses).
  const char* repeat = std::getenv("BENCH_PLANNING_REPLAY_REPEAT");
  const int times = repeat ? std::max(1, std::atoi(repeat)) : 1;
  double fastest = 0.0;
  for (int t = 0; t < times; ++t) {
    const SceneChecker scene(checker, env, options);
    ReplayCount again;  // (the first replay counts, in the order the calls were made)
    const auto begin = std::chrono::steady_clock::now();
    replay_calls(scene, found->second, t == 0 ? count : again);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
    fastest = t == 0 ? seconds : std::min(fastest, seconds);
  }
  count.seconds += fastest;
}

void print_replay(const std::string& robot, const std::string& row, const CollisionChecker& checker, const ReplayCount& r) {
  if (r.states + r.motions == 0) return;
  std::printf("%s replayed, %s: %zu states (%zu free), %zu motions (%zu free, %zu intervals; colliding ones' last valid fractions "
              "sum to %.17g; self pairs' exact growth %g m, timed at load, %s) in %.4f s\n",
              robot.c_str(), row.c_str(), r.states, r.free_states, r.motions, r.free_motions, r.intervals, r.fractions,
              checker.accelerators().pair_exact_growth(),
              std::getenv("BENCH_PLANNING_PAIR_GROWTH") ? "replaced by BENCH_PLANNING_PAIR_GROWTH" : "kept", r.seconds);
}

}  // namespace bvh_collision::bench
