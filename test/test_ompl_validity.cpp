// OMPL over the checker in-process (planning/ompl_validity.h): RRTConnect plans the demo arm
// around a pillar its straight motion runs into, and every segment of the path it returns is free
// by the certified check_motion and by a dense sweep (an independent brute-force check: states
// 1e-3 rad apart, each checked exactly); the validators agree with the checker's own queries,
// count the planner's calls, and refuse a group or state that does not fit the robot.
#include <gtest/gtest.h>

#include <ompl/base/Planner.h>
#include <ompl/base/ScopedState.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/SimpleSetup.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "bvh_collision/planning/ompl_validity.h"
#include "checker_fixtures.h"
#include "planning_scenes.h"
#include "advancement_oracle.h"

namespace bvh_collision::planning {
namespace {

namespace ob = ompl::base;
namespace og = ompl::geometric;

// The demo arm's scene: the pillar of demo.launch (0.12 x 0.12 x 0.8 m at (0.45, 0.35, 0.4)).
std::shared_ptr<const Environment> pillar_scene() {
  auto env = std::make_shared<Environment>(0.02);
  env->add_object("pillar", ObjectShape::box(Vec3(0.12, 0.12, 0.8)), Transform::Translation(Vec3(0.45, 0.35, 0.4)));
  return env;
}

const std::vector<std::string> kArm = {"joint1", "joint2", "joint3", "joint4", "joint5", "joint6"};
// Leaning forward at 1 rad, swung from +x past the pillar (at about 0.66 rad of joint1).
const std::vector<double> kStart = {0.0, 1.0, 0.0, 0.0, 0.0, 0.0}, kGoal = {1.3, 1.0, 0.0, 0.0, 0.0, 0.0};

std::shared_ptr<CheckerPlanningContext> demo_context(double tolerance = 0.01) {
  CheckerOptions options;
  options.proxy_levels = {0.01, 0.02};
  const CollisionChecker checker = test::demo_arm_checker(options);
  std::vector<double> base(checker.model().variable_count(), 0.0);
  auto context = std::make_shared<CheckerPlanningContext>(checker, pillar_scene(), JointGroup::of(checker.model(), kArm), base);
  context->tolerance = tolerance;
  return context;
}

// Exact checks every `step` of joint motion (max norm), both ends included: a brute-force sweep.
bool dense_sweep_free(const CheckerPlanningContext& c, const std::vector<double>& a, const std::vector<double>& b,
                      double step) {
  double longest = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) longest = std::max(longest, std::abs(b[i] - a[i]));
  const int n = std::max(1, static_cast<int>(std::ceil(longest / step)));
  ob::RealVectorStateSpace space(static_cast<unsigned>(a.size()));
  ob::State* s = space.allocState();
  bool free = true;
  for (int k = 0; k <= n && free; ++k) {
    double* v = s->as<ob::RealVectorStateSpace::StateType>()->values;
    for (std::size_t i = 0; i < a.size(); ++i) v[i] = a[i] + (b[i] - a[i]) * k / n;
    const std::vector<double> q = c.full_state(s);
    free = !c.checker.check_self(q.data()).collision && !c.checker.check_environment(q.data(), *c.environment).collision;
  }
  space.freeState(s);
  return free;
}

TEST(OmplValidity, RrtConnectPlansAroundThePillarAndEverySegmentIsFree) {
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  ompl::RNG::setSeed(3);
  const auto context = demo_context();
  og::SimpleSetup setup(context->group.make_space());
  setup.setStateValidityChecker(std::make_shared<CheckerStateValidityChecker>(setup.getSpaceInformation(), context));
  setup.getSpaceInformation()->setMotionValidator(std::make_shared<CheckerMotionValidator>(setup.getSpaceInformation(), context));
  ob::ScopedState<> start(setup.getStateSpace()), goal(setup.getStateSpace());
  for (std::size_t i = 0; i < kArm.size(); ++i) start[i] = kStart[i], goal[i] = kGoal[i];
  setup.setStartAndGoalStates(start, goal);
  setup.setPlanner(std::make_shared<og::RRTConnect>(setup.getSpaceInformation()));

  // The straight motion runs into the pillar: planning is needed.
  ASSERT_FALSE(setup.getSpaceInformation()->checkMotion(start.get(), goal.get()));
  ASSERT_FALSE(dense_sweep_free(*context, kStart, kGoal, 1e-3));
  // Untimed by default: the checks are counted, no clock is read.
  ASSERT_TRUE(setup.getSpaceInformation()->isValid(start.get()));
  EXPECT_GT(context->counters->states.load(), 0u);
  EXPECT_EQ(context->counters->seconds(), 0.0);
  context->counters->reset();
  context->counters->timed = true;
  // Bounded by work, not time (a seeded RRTConnect does the same work on any machine): it solves
  // this in well under a hundred checks.
  const auto checks = [&] { return context->counters->states.load() + context->counters->motions.load(); };
  ASSERT_EQ(setup.solve(ob::PlannerTerminationCondition([&] { return checks() > 20000; })), ob::PlannerStatus::EXACT_SOLUTION);
  setup.simplifySolution();
  EXPECT_GT(context->counters->states.load(), 0u);
  EXPECT_GT(context->counters->motions.load(), 0u);
  EXPECT_GT(context->counters->seconds(), 0.0);

  const og::PathGeometric& path = setup.getSolutionPath();
  ASSERT_GE(path.getStateCount(), 3u) << "a detour has at least one waypoint between start and goal";
  for (std::size_t w = 0; w + 1 < path.getStateCount(); ++w) {
    const std::vector<double> a = context->full_state(path.getState(w)), b = context->full_state(path.getState(w + 1));
    MotionRequest certified;  // by conservative advancement, written apart from the engine
    EXPECT_TRUE(test::advancement_motion(context->checker, a.data(), b.data(), *context->environment, certified).valid) << "segment " << w;
    std::vector<double> ga(a.begin(), a.begin() + 6), gb(b.begin(), b.begin() + 6);
    EXPECT_TRUE(dense_sweep_free(*context, ga, gb, 1e-3)) << "segment " << w;
  }
}

TEST(OmplValidity, ValidatorsAgreeWithTheCheckersOwnQueries) {
  const auto context = demo_context(0.0);
  auto si = std::make_shared<ob::SpaceInformation>(context->group.make_space());
  CheckerStateValidityChecker states(si, context);
  CheckerMotionValidator motions(si, context);
  ob::ScopedState<> s(si->getStateSpace()), t(si->getStateSpace());
  std::mt19937_64 rng(5);
  int valid = 0, invalid = 0;
  for (int i = 0; i < test::sized(200); ++i) {
    s.random();
    const std::vector<double> q = context->full_state(s.get());
    const bool colliding = context->checker.check_self(q.data()).collision ||
                           context->checker.check_environment(q.data(), *context->environment).collision;
    EXPECT_EQ(states.isValid(s.get()), !colliding) << i;
    (colliding ? invalid : valid)++;
    const double clearance = states.clearance(s.get());
    if (colliding) {
      EXPECT_EQ(clearance, 0.0);
    } else {
      EXPECT_GT(clearance, 0.0);
    }
  }
  EXPECT_GT(valid, 0);
  EXPECT_GT(invalid, 0);
  // The motion validator: the last valid state lies on the segment at the fraction it reports,
  // and the state there is free.
  for (std::size_t i = 0; i < kArm.size(); ++i) s[i] = kStart[i], t[i] = kGoal[i];
  ob::State* last = si->allocState();
  std::pair<ob::State*, double> last_valid(last, -1.0);
  ASSERT_FALSE(motions.checkMotion(s.get(), t.get(), last_valid));
  EXPECT_GT(last_valid.second, 0.0);
  EXPECT_LT(last_valid.second, 1.0);
  EXPECT_TRUE(states.isValid(last));
  EXPECT_EQ(motions.getCheckedMotionCount(), 1u);
  EXPECT_EQ(motions.getInvalidMotionCount(), 1u);
  si->freeState(last);
}

// One adapter over either context: the in-process validator takes several motions in one call
// as the service-backed one does (a lazy planner's candidate path), each answered as checkMotion
// answers it alone, and counted.
TEST(OmplValidity, SeveralMotionsInOneCallAnswerAsEachAlone) {
  const auto context = demo_context();
  auto si = std::make_shared<ob::SpaceInformation>(context->group.make_space());
  CheckerMotionValidator motions(si, context);
  CheckerMotionValidator one_by_one(si, context);
  std::vector<ob::State*> states;
  std::vector<std::pair<const ob::State*, const ob::State*>> pairs;
  ob::ScopedState<> s(si->getStateSpace());
  for (int i = 0; i < 2 * test::sized(40); ++i) {
    s.random();
    states.push_back(si->cloneState(s.get()));
  }
  for (std::size_t i = 0; i + 1 < states.size(); i += 2) pairs.emplace_back(states[i], states[i + 1]);
  const std::uint64_t before = context->counters->motions;
  const std::vector<bool> answers = motions.checkMotions(pairs);
  ASSERT_EQ(answers.size(), pairs.size());
  EXPECT_EQ(context->counters->motions - before, pairs.size());
  int free = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    EXPECT_EQ(answers[i], one_by_one.checkMotion(pairs[i].first, pairs[i].second)) << i;
    free += answers[i];
  }
  EXPECT_GT(free, 0);
  EXPECT_LT(free, static_cast<int>(pairs.size()));
  EXPECT_EQ(motions.getCheckedMotionCount(), pairs.size());
  EXPECT_EQ(motions.getValidMotionCount(), static_cast<unsigned>(free));
  for (ob::State* state : states) si->freeState(state);
}

// At the default tolerance (1 cm): a state answered valid is free on the exact geometry, one
// answered invalid is within 1 cm of a collision.
TEST(OmplValidity, AtTheDefaultToleranceValidIsFree) {
  const auto context = demo_context();
  EXPECT_EQ(CheckerPlanningContext(context->checker, context->environment, context->group, context->base_state).tolerance, 0.01);
  auto si = std::make_shared<ob::SpaceInformation>(context->group.make_space());
  CheckerStateValidityChecker states(si, context);
  ob::ScopedState<> s(si->getStateSpace());
  int valid = 0, near = 0;
  for (int i = 0; i < test::sized(300); ++i) {
    s.random();
    const std::vector<double> q = context->full_state(s.get());
    SelfCollisionRequest self;
    self.distance = true;
    EnvironmentRequest env;
    env.distance = true;
    const SelfCollisionResult rs = context->checker.check_self(q.data(), self);
    const EnvironmentResult re = context->checker.check_environment(q.data(), *context->environment, env);
    const double clearance = rs.collision || re.collision ? 0.0 : std::min(rs.min_distance, re.min_distance);
    if (states.isValid(s.get())) {
      ++valid;
      EXPECT_GT(clearance, 0.0) << i;
    } else {
      EXPECT_LE(clearance, 0.01 + 1e-9) << i;
      near += clearance > 0.0;
    }
  }
  EXPECT_GT(valid, 0);
  std::cout << valid << " valid; " << near << " free states within 1 cm answered invalid\n";
}

// The demo arm leaning forward (joint2 at 1 rad) swung by joint1 alone past a pillar whose
// nearest face its hand passes 5.0 mm from (exact distances every 6.5e-5 rad of the swing): a
// passage the exact check lets through and a 1 cm tolerance may close.
std::shared_ptr<CheckerPlanningContext> five_millimetre_pass(double tolerance) {
  CheckerOptions options;
  options.proxy_levels = {0.01, 0.02};
  const CollisionChecker checker = test::demo_arm_checker(options);
  auto env = std::make_shared<Environment>(0.02);
  env->add_object("pillar", ObjectShape::box(Vec3(0.12, 0.12, 0.8)), Transform::Translation(Vec3(0.729, 0.58, 0.4)));
  std::vector<double> base(checker.model().variable_count(), 0.0);
  base[1] = 1.0;
  auto context = std::make_shared<CheckerPlanningContext>(checker, env, JointGroup::of(checker.model(), {"joint1"}), base);
  context->tolerance = tolerance;
  return context;
}

// A planner that only ever asks the straight motion from start to goal: what a search does at a
// passage it must cross, without the luck of where its samples land.
class StraightMotionPlanner : public ob::Planner {
 public:
  explicit StraightMotionPlanner(const ob::SpaceInformationPtr& si) : ob::Planner(si, "StraightMotion") {}
  ob::PlannerStatus solve(const ob::PlannerTerminationCondition& ptc) override {
    checkValidity();
    const ob::State* start = pis_.nextStart();
    if (start != nullptr) start_ = start;
    const ob::State* goal = pis_.nextGoal();
    if (goal != nullptr) goal_ = goal;
    while (!ptc) {
      if (!si_->checkMotion(start_, goal_)) continue;
      auto path = std::make_shared<og::PathGeometric>(si_, start_, goal_);
      pdef_->addSolutionPath(path, false, 0.0, getName());
      return ob::PlannerStatus::EXACT_SOLUTION;
    }
    return ob::PlannerStatus::TIMEOUT;
  }
  void clear() override {
    ob::Planner::clear();
    start_ = goal_ = nullptr;
  }

 private:
  const ob::State* start_ = nullptr;
  const ob::State* goal_ = nullptr;
};

// The pass from joint1 at 0 to 1.3 rad, planned by `Planner` over the context's validators.
template <class Planner>
og::SimpleSetup pass_setup(const std::shared_ptr<CheckerPlanningContext>& context) {
  og::SimpleSetup setup(context->group.make_space());
  const auto si = setup.getSpaceInformation();
  setup.setStateValidityChecker(std::make_shared<CheckerStateValidityChecker>(si, context));
  si->setMotionValidator(std::make_shared<CheckerMotionValidator>(si, context));
  ob::ScopedState<> start(setup.getStateSpace()), goal(setup.getStateSpace());
  start[0] = 0.0, goal[0] = 1.3;
  setup.setStartAndGoalStates(start, goal);
  setup.setPlanner(std::make_shared<Planner>(si));
  setup.setup();
  context->counters->reset();
  return setup;
}

// solve_tolerance_first until the context's counters reach `limit` motions.
SearchOutcome solve_within(og::SimpleSetup& setup, const std::shared_ptr<CheckerPlanningContext>& context, std::uint64_t limit,
                           std::uint64_t motions_at_tolerance) {
  const ob::PlannerTerminationCondition ptc([context, limit] { return context->counters->motions.load() >= limit; });
  return solve_tolerance_first(setup, *context, ptc, motions_at_tolerance);
}

// An outcome's status, whether it went on exact, and its motions at the tolerance and exact.
void expect_outcome(const SearchOutcome& o, ob::PlannerStatus::StatusType status, bool went_exact, std::uint64_t at_tolerance,
                    std::uint64_t exact) {
  EXPECT_EQ(o.status, status);
  EXPECT_EQ(o.went_exact, went_exact);
  EXPECT_EQ(o.motions_at_tolerance, at_tolerance);
  EXPECT_EQ(o.motions_exact, exact);
}

// A tolerance answers "colliding" within it of a collision: on a passage a few millimetres wider
// than the robot a search at 1 cm can ask forever. solve_tolerance_first goes on with exact answers
// after a number of motions (the planner's work kept: what the tolerance let through is free
// exactly too), and hands the context back at its tolerance.
TEST(OmplValidity, ASearchTheToleranceStallsGoesOnExact) {
  const auto context = five_millimetre_pass(0.01);
  const auto exact = five_millimetre_pass(0.0);
  ob::SpaceInformation si(context->group.make_space());
  ob::ScopedState<> a(si.getStateSpace()), b(si.getStateSpace());
  a[0] = 0.0, b[0] = 1.3;
  // The premises: both ends farther than the tolerance from everything; the swing free by the
  // certified check, by the conservative advancement written apart from it, and a colliding
  // answer at 1 cm.
  EXPECT_GT(exact->clearance(a.get()), 0.01);
  EXPECT_GT(exact->clearance(b.get()), 0.01);
  ASSERT_TRUE(exact->check_motion(a.get(), b.get(), false).valid);
  const std::vector<double> qa = exact->full_state(a.get()), qb = exact->full_state(b.get());
  ASSERT_TRUE(test::advancement_motion(exact->checker, qa.data(), qb.data(), *exact->environment, MotionRequest()).valid);
  ASSERT_FALSE(context->check_motion(a.get(), b.get(), false).valid);

  // At the tolerance alone the search never crosses: 2,000 motions asked, no path.
  const auto motions = [&] { return context->counters->motions.load(); };
  {
    og::SimpleSetup setup = pass_setup<StraightMotionPlanner>(context);
    EXPECT_EQ(setup.solve(ob::PlannerTerminationCondition([&] { return motions() >= 2000; })), ob::PlannerStatus::TIMEOUT);
  }
  // Tolerance first for 50 motions, then exact: crossed at the 51st.
  og::SimpleSetup setup = pass_setup<StraightMotionPlanner>(context);
  expect_outcome(solve_within(setup, context, 2000, 50), ob::PlannerStatus::EXACT_SOLUTION, true, 50, 1);
  EXPECT_EQ(motions(), 51u);
  EXPECT_FALSE(context->check_motion(a.get(), b.get(), false).valid) << "the context is back at its tolerance";
  // A limit that comes first ends the search at the tolerance; a tolerance of 0 has nothing to
  // go on to.
  og::SimpleSetup limited = pass_setup<StraightMotionPlanner>(context);
  expect_outcome(solve_within(limited, context, 30, 50), ob::PlannerStatus::TIMEOUT, false, 30, 0);
  og::SimpleSetup at_zero = pass_setup<StraightMotionPlanner>(exact);
  expect_outcome(solve_within(at_zero, exact, 2000, 50), ob::PlannerStatus::EXACT_SOLUTION, false, 0, 1);
}

// RRTConnect through the same pass, sent on exact after its first iteration with its trees kept:
// solved, and every segment of its path free by the conservative advancement. (An iteration whose
// extension lands within the tolerance of the pillar can cross at the tolerance, its end being
// that close already: ten searches, of which some go on exact; OMPL's seed is not ours to set
// here, another test of this binary drew from it first.)
TEST(OmplValidity, RrtConnectGoesOnExactWithItsTreesAndItsPathIsFree) {
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  const auto context = five_millimetre_pass(0.01);
  const auto motions = [&] { return context->counters->motions.load(); };
  int went_exact = 0;
  for (int attempt = 0; attempt < 10; ++attempt) {
    og::SimpleSetup setup = pass_setup<og::RRTConnect>(context);
    const SearchOutcome outcome = solve_within(setup, context, 20000, 1);
    ASSERT_EQ(outcome.status, ob::PlannerStatus::EXACT_SOLUTION) << attempt;
    EXPECT_GE(outcome.motions_at_tolerance, 1u);
    EXPECT_EQ(outcome.motions_at_tolerance + outcome.motions_exact, motions());
    EXPECT_EQ(outcome.went_exact, outcome.motions_exact > 0);
    went_exact += outcome.went_exact;
    const og::PathGeometric& path = setup.getSolutionPath();
    for (std::size_t w = 0; w + 1 < path.getStateCount(); ++w) {
      const std::vector<double> a = context->full_state(path.getState(w)), b = context->full_state(path.getState(w + 1));
      EXPECT_TRUE(test::advancement_motion(context->checker, a.data(), b.data(), *context->environment, MotionRequest()).valid)
          << attempt << ", segment " << w;
    }
  }
  EXPECT_GT(went_exact, 0);
  std::cout << went_exact << " of 10 searches went on exact\n";
}

// Every segment of `path` free by the conservative advancement (written apart from the engine).
int colliding_segments(const CheckerPlanningContext& c, const og::PathGeometric& path) {
  int colliding = 0;
  for (std::size_t w = 0; w + 1 < path.getStateCount(); ++w) {
    const std::vector<double> a = c.full_state(path.getState(w)), b = c.full_state(path.getState(w + 1));
    colliding += !test::advancement_motion(c.checker, a.data(), b.data(), *c.environment, MotionRequest()).valid;
  }
  return colliding;
}

// bench_planning's ur5e problem 67 at 10 mm (scene seed 2026, OMPL seed 1; 2026-12-07): the search
// went on exact after 1,000 motions and found this path, whose segments pass within the tolerance
// of the scene's cage bars.
const std::vector<std::vector<double>> kFoundExact = {
    {4.3954849214839165, -5.0497126604425571, 1.5324719453067779, -3.8643860164719355, -5.7407398173451263, 6.1037783975646001},
    {3.7589954754163664, -2.6773040596173652, -1.0233705660012475, 0.2431845183443162, -5.3858845900499457, 4.2069282374315362},
    {3.9789737873324493, -3.639431606491125, 0.87410247482891146, -0.070705006355911371, -2.5478908564840816, -0.31354208183177867},
    {3.6569943170796098, -4.1702370002846978, -0.87913588714956914, -2.2423789617523386, 1.6273324219932483, -0.498986102142851},
    {4.4397235739794372, -2.1383372918188552, -2.2160793344756051, -3.8609041292209665, 5.4054347853105735, -1.5799099102692109},
    {3.6148116336422986, -0.74349612293167322, -2.1560228376862471, 1.5390997899813033, 4.4793868643558614, -2.2972629125044204},
    {2.5344965022659061, -1.085897906028882, 2.2148628997113788, -0.48861300098738214, 5.4981776049333888, -5.0583053168113139},
    {1.781446637285045, -1.5412196188325282, 1.6545725764153945, 0.99470978727826243, 0.44495051052749002, -4.0695323165070221},
    {2.7764684562298663, 1.5410582229969387, -0.24111316400075133, -2.1104619557730269, 1.2364510579205996, -2.7696267023727152},
    {-1.1713819731955866, 0.8113323189317958, 1.084344630448369, -0.3606901488890486, 4.6962678904869799, -3.2745778124222076},
    {0.0042415259413486339, 3.3276644162269786, 2.6806145582126613, 4.1578356323375569, 5.578711420036262, -4.5799488138320736}};

// A path found on exact answers may pass closer than the tolerance to an obstacle. OMPL's simplifier
// ends by re-checking every segment (PathGeometric::checkAndRepair) and "repairs" one its
// validators reject by sampling states near it; when none serves, it leaves the last sampled state
// in the path, with motions no check found free, and SimpleSetup::simplifySolution drops its
// verdict: in the benchmark this path came back colliding by both re-checks. simplify_certified
// simplifies on the answers the search ended on, and a result its simplifier rejects goes back
// to the path found, simplified exact.
TEST(OmplValidity, APathFoundExactIsSimplifiedExactAndStaysFree) {
  ompl::msg::setLogLevel(ompl::msg::LOG_ERROR);
  CheckerOptions options;
  options.proxy_levels = {0.005, 0.01, 0.02};
  // No timing at load: the 1 cm answers below do not depend on how busy the machine is (a
  // calibrated checker picks the self pairs' exact growth and exact pairs by timing them).
  options.calibrate_proxies = false;
  const CollisionChecker checker = test::load_as_moveit("ur5e", options);
  const auto env = std::make_shared<const Environment>(test::generate_scene(2026, 67).environment());
  auto context = std::make_shared<CheckerPlanningContext>(checker, env, JointGroup::of(checker.model(), {}), kFoundExact.front());
  og::SimpleSetup setup(context->group.make_space());
  const auto si = setup.getSpaceInformation();
  setup.setStateValidityChecker(std::make_shared<CheckerStateValidityChecker>(si, context));
  si->setMotionValidator(std::make_shared<CheckerMotionValidator>(si, context));
  ob::ScopedState<> start(si->getStateSpace()), goal(si->getStateSpace());
  for (std::size_t i = 0; i < 6; ++i) start[i] = kFoundExact.front()[i], goal[i] = kFoundExact.back()[i];
  setup.setStartAndGoalStates(start, goal);
  setup.setPlanner(std::make_shared<og::RRTConnect>(si));
  setup.setup();
  og::PathGeometric found(si);
  ob::ScopedState<> s(si->getStateSpace());
  for (const auto& q : kFoundExact) {
    for (std::size_t i = 0; i < 6; ++i) s[i] = q[i];
    found.append(s.get());
  }
  ASSERT_EQ(colliding_segments(*context, found), 0) << "found free";
  // Its eighth segment the tolerance rejects; OMPL's final check and repair at the tolerance mostly
  // cannot repair it, and leaves sampled states in its place whose motions collide.
  ASSERT_FALSE(si->checkMotion(found.getState(7), found.getState(8)));
  int corrupted = 0;
  for (int draw = 0; draw < 5; ++draw) {
    og::PathGeometric path = found;
    path.checkAndRepair(100);
    corrupted += colliding_segments(*context, path) > 0;
  }
  EXPECT_GT(corrupted, 0);
  std::cout << "OMPL's check and repair at 1 cm left a colliding path in " << corrupted << " of 5 draws\n";

  // simplify_certified on the path found exact: simplified exact, free, accepted on those answers.
  SearchOutcome search;
  search.status = ob::PlannerStatus::EXACT_SOLUTION;
  search.went_exact = true;
  const auto simplify_and_check = [&](const og::PathGeometric& from, const std::string& what) {
    setup.getProblemDefinition()->clearSolutionPaths();
    setup.getProblemDefinition()->addSolutionPath(std::make_shared<og::PathGeometric>(from));
    const SimplifyOutcome simplified = simplify_certified(setup, *context, search);
    const og::PathGeometric& path = setup.getSolutionPath();
    EXPECT_FALSE(context->exact.load()) << what << ": the context is back at its tolerance";
    EXPECT_TRUE(simplified.simplified) << what;
    EXPECT_EQ(colliding_segments(*context, path), 0) << what;
    context->exact = simplified.exact;
    EXPECT_TRUE(path.check()) << what << ": every segment free on the answers it was simplified on";
    context->exact = false;
    return simplified;
  };
  for (int draw = 0; draw < 3; ++draw) {
    const SimplifyOutcome simplified = simplify_and_check(found, "went exact, draw " + std::to_string(draw));
    EXPECT_TRUE(simplified.exact);
    EXPECT_FALSE(simplified.restored) << "exact answers accept a path found exact";
  }
  // A caller who says the path was found at the tolerance (it was not): its eighth to tenth states
  // (the rejected segment and the next), simplified at 1 cm, which OMPL's simplifier sometimes
  // rejects (1 of 10 draws when this test was written); a rejected result goes back and is
  // simplified exact. (With OMPL's simplifier at the tolerance and its verdict dropped, as before
  // simplify_certified, this test failed in 3 of 3 runs: one or two of its 13 draws left a
  // colliding segment.)
  search.went_exact = false;
  og::PathGeometric tail(si);
  for (std::size_t w = 7; w < found.getStateCount() - 1; ++w) tail.append(found.getState(w));
  int restored = 0;
  for (int draw = 0; draw < 10; ++draw) {
    const SimplifyOutcome simplified = simplify_and_check(tail, "at 1 cm, draw " + std::to_string(draw));
    EXPECT_EQ(simplified.exact, simplified.restored);
    restored += simplified.restored;
  }
  std::cout << restored << " of 10 simplifications at 1 cm went back to the path found\n";
}

TEST(OmplValidity, BadGroupsAndStatesAreNamed) {
  const CollisionChecker checker = test::demo_arm_checker();
  EXPECT_THROW(JointGroup::of(checker.model(), {"joint1", "no_such_joint"}), std::invalid_argument);
  EXPECT_THROW(JointGroup::of(checker.model(), {"hand_joint"}), std::invalid_argument) << "a fixed joint is no variable";
  const JointGroup all = JointGroup::of(checker.model());
  EXPECT_EQ(all.size(), checker.model().variable_count());
  EXPECT_EQ(all.lower[0], -2.9);
  EXPECT_EQ(all.upper[0], 2.9);
  EXPECT_THROW(CheckerPlanningContext(checker, pillar_scene(), all, std::vector<double>(3, 0.0)), std::invalid_argument);
  EXPECT_THROW(CheckerPlanningContext(checker, nullptr, all, std::vector<double>(checker.model().variable_count(), 0.0)),
               std::invalid_argument);
}

}  // namespace
}  // namespace bvh_collision::planning
