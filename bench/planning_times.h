// bench_planning's timing: every validity call timed on its own (for medians), OMPL's simplifier's
// motions apart, and where one problem's or many problems' plan time went.
#pragma once

#include <ompl/base/MotionValidator.h>
#include <ompl/base/StateValidityChecker.h>

#include <array>
#include <cstddef>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

namespace bvh_collision {
namespace bench {

struct CallTimes {
  std::vector<double> states, motions;  // microseconds per call
  double outside_motions_us = 0.0;      // the state calls not made inside a motion call, summed
  // The simplifier's motion calls (while `simplifying`), colliding [0] and free [1]: how many, and
  // their time in microseconds.
  bool simplifying = false;
  std::array<long, 2> simplifier_motions{};
  std::array<double, 2> simplifier_motions_us{};
  void motion(double us, bool valid);
};

double now_us();

class TimedValidity : public ompl::base::StateValidityChecker {
 public:
  TimedValidity(const ompl::base::SpaceInformationPtr& si, std::function<bool(const ompl::base::State*)> valid, CallTimes* times)
      : ompl::base::StateValidityChecker(si), valid_(std::move(valid)), times_(times) {}
  bool isValid(const ompl::base::State* s) const override;

 private:
  std::function<bool(const ompl::base::State*)> valid_;
  CallTimes* times_;
};

class TimedMotions : public ompl::base::MotionValidator {
 public:
  using Hook = std::function<void(const ompl::base::State*, const ompl::base::State*, bool)>;
  TimedMotions(const ompl::base::SpaceInformationPtr& si, std::shared_ptr<ompl::base::MotionValidator> inner, CallTimes* times,
               Hook hook = {})
      : ompl::base::MotionValidator(si), inner_(std::move(inner)), times_(times), hook_(std::move(hook)) {}
  bool checkMotion(const ompl::base::State* a, const ompl::base::State* b) const override;
  bool checkMotion(const ompl::base::State* a, const ompl::base::State* b, std::pair<ompl::base::State*, double>& last) const override;

 private:
  std::shared_ptr<ompl::base::MotionValidator> inner_;
  CallTimes* times_;
  Hook hook_;
};

// One problem's plan as run: its time, the simplifier's part, and the time inside validity calls.
struct ProblemTimes {
  double seconds = 0.0, simplify_seconds = 0.0, check_seconds = 0.0;
};

// A tally's calls before a plan, to tell one problem's calls from the others'.
struct CallMark {
  std::size_t states = 0, motions = 0;
  double outside_motions_us = 0.0;
  std::array<long, 2> simplifier_motions{};
  std::array<double, 2> simplifier_motions_us{};
};
CallMark mark(const CallTimes& c);

// Where a checker's plan time went: inside its validity calls (our checks with the adapter's
// state layout, or FCL's), in OMPL's simplifier, and the rest (OMPL's own sampling, nearest
// neighbours and bookkeeping). Over all its problems the few slowest weigh most (a failed plan's
// ten seconds are mostly OMPL's nearest neighbours); over the middle half of its problems by plan
// time (the median plan's neighbours) the figures say where a typical plan goes.
struct TimeShares {
  double checks = 0.0, simplifier = 0.0;  // fractions of the plan time
};
TimeShares time_shares(std::vector<ProblemTimes> problems, bool middle_half);

}  // namespace bench
}  // namespace bvh_collision
