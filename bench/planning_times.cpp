// bench_planning's timing (planning_times.h).
#include "planning_times.h"

#include <algorithm>
#include <chrono>

namespace bvh_collision {
namespace bench {
namespace {

// Inside a motion call (FCL's discrete validator calls the state checker): its state calls are
// the motion's time, not counted twice in the time shares.
thread_local int motion_depth = 0;

}  // namespace

void CallTimes::motion(double us, bool valid) {
  motions.push_back(us);
  if (!simplifying) return;
  ++simplifier_motions[valid];
  simplifier_motions_us[valid] += us;
}

double now_us() {
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

bool TimedValidity::isValid(const ompl::base::State* s) const {
  const double t0 = now_us();
  const bool v = valid_(s);
  const double us = now_us() - t0;
  times_->states.push_back(us);
  if (motion_depth == 0) times_->outside_motions_us += us;
  return v;
}

bool TimedMotions::checkMotion(const ompl::base::State* a, const ompl::base::State* b) const {
  if (hook_) hook_(a, b, false);
  const double t0 = now_us();
  ++motion_depth;
  const bool v = inner_->checkMotion(a, b);
  --motion_depth;
  times_->motion(now_us() - t0, v);
  return v;
}

bool TimedMotions::checkMotion(const ompl::base::State* a, const ompl::base::State* b, std::pair<ompl::base::State*, double>& last) const {
  if (hook_) hook_(a, b, true);
  const double t0 = now_us();
  ++motion_depth;
  const bool v = inner_->checkMotion(a, b, last);
  --motion_depth;
  times_->motion(now_us() - t0, v);
  return v;
}

CallMark mark(const CallTimes& c) {
  return {c.states.size(), c.motions.size(), c.outside_motions_us, c.simplifier_motions, c.simplifier_motions_us};
}

TimeShares time_shares(std::vector<ProblemTimes> problems, bool middle_half) {
  std::sort(problems.begin(), problems.end(), [](const ProblemTimes& a, const ProblemTimes& b) { return a.seconds < b.seconds; });
  const std::size_t n = problems.size();
  const std::size_t first = middle_half ? n / 4 : 0, end = middle_half ? std::max(first + 1, n - n / 4) : n;
  ProblemTimes sum;
  for (std::size_t i = first; i < std::min(end, n); ++i) {
    sum.seconds += problems[i].seconds;
    sum.simplify_seconds += problems[i].simplify_seconds;
    sum.check_seconds += problems[i].check_seconds;
  }
  if (!(sum.seconds > 0)) return {};
  return {sum.check_seconds / sum.seconds, sum.simplify_seconds / sum.seconds};
}

}  // namespace bench
}  // namespace bvh_collision
