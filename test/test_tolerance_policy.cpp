// The tolerance policy (narrowphase/tolerance_policy.h): the table of which method may answer,
// for every kind of counterpart and tolerance class, and on a robot that the level it picks keeps
// docs/design.md's contract (collision whenever d <= padding, free whenever d > padding + eps)
// for every kind pair: link x link, link x object, link x octree.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <random>
#include <tuple>
#include <vector>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"
#include "bvh_collision/octree/scan.h"
#include "checker_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

constexpr double kRounding = 1e-9;

struct Row {
  Counterpart other;
  bool boolean, solids, motion, field;
  double tolerance;
  double decide;  // expected ProxyUse
};

// The policy as a table, written out: read it as the documentation of the header.
const Row kTable[] = {
    // Exact (tolerance 0): the proxies only prune, whatever the question.
    {Counterpart::kLink, true, true, false, false, 0.0, 0.0},
    {Counterpart::kObject, true, true, false, false, 0.0, 0.0},
    {Counterpart::kOctree, true, true, false, true, 0.0, 0.0},
    {Counterpart::kLink, true, true, true, false, 0.0, 0.0},
    // A boolean question on solids at 1 cm: a level's error is e against a link, e / 2 against
    // an obstacle.
    {Counterpart::kLink, true, true, false, false, 0.01, 0.01},
    {Counterpart::kObject, true, true, false, false, 0.01, 0.02},
    {Counterpart::kOctree, true, true, false, true, 0.01, 0.02},
    // The octree without its distance field: exact (the proxies' leaf test reads the field).
    {Counterpart::kOctree, true, true, false, false, 0.01, 0.0},
    // Distances and contacts, and surfaces only: exact.
    {Counterpart::kLink, false, true, false, false, 0.01, 0.0},
    {Counterpart::kObject, false, true, false, false, 0.01, 0.0},
    {Counterpart::kOctree, false, true, false, true, 0.01, 0.0},
    {Counterpart::kLink, true, false, false, false, 0.01, 0.0},
    {Counterpart::kOctree, true, false, false, true, 0.01, 0.0},
    // Certified motions: the levels down to the coarsest that decides, as a state's.
    {Counterpart::kLink, true, true, true, false, 0.01, 0.01},
    {Counterpart::kObject, true, true, true, false, 0.01, 0.02},
    {Counterpart::kOctree, true, true, true, true, 0.01, 0.02},
};

ToleranceQuestion question_of(const Row& r) {
  ToleranceQuestion q{r.tolerance, r.other};
  q.boolean = r.boolean;
  q.solids = r.solids;
  q.motion = r.motion;
  q.octree_field = r.field;
  return q;
}

TEST(TolerancePolicy, TheTable) {
  for (const Row& r : kTable) {
    const ProxyUse use = proxy_use(question_of(r));
    EXPECT_EQ(use.decide_up_to, r.decide) << "row " << (&r - kTable);
  }
}

// A certified motion's interval that still fails counts as colliding only when the level's error
// against the counterpart (e against a link's proxies, e/2 against an obstacle) and the growth fit
// the tolerance: never at tolerance 0; at the level a motion walks down to by default (the
// tolerance itself) a growth up to half the tolerance against an obstacle and none against a link;
// at half the tolerance, half of it against a link.
TEST(TolerancePolicy, AFailingIntervalCountsAsCollidingOnlyWithinTheTolerance) {
  for (const double t : {0.0, 1e-4, 0.003, 0.01, 0.05}) {
    ToleranceQuestion q{t, Counterpart::kLink};
    q.motion = true;
    const double preferred = proxy_use(q).decide_up_to;
    for (const double level : {0.0, preferred, 0.002, 0.005, 0.01, 0.02}) {
      for (const double growth : {0.0, 1e-6, t / 4, t / 2, t}) {
        for (const Counterpart other : {Counterpart::kLink, Counterpart::kObject}) {
          const double error = other == Counterpart::kLink ? level : level / 2;
          EXPECT_EQ(interval_within_tolerance(level, other, growth, t), error + growth <= t) << t << " " << level << " " << growth;
          if (t == 0.0 && (level > 0.0 || growth > 0.0)) {
            EXPECT_FALSE(interval_within_tolerance(level, other, growth, t));
          }
        }
      }
    }
    if (t > 0.0) {
      EXPECT_EQ(preferred, t);
      EXPECT_TRUE(interval_within_tolerance(preferred, Counterpart::kObject, t / 2, t));
      EXPECT_FALSE(interval_within_tolerance(preferred, Counterpart::kObject, t / 2 * (1 + 1e-9), t));
      EXPECT_TRUE(interval_within_tolerance(preferred, Counterpart::kLink, 0.0, t));
      EXPECT_FALSE(interval_within_tolerance(preferred, Counterpart::kLink, 1e-12, t));
      EXPECT_TRUE(interval_within_tolerance(t / 2, Counterpart::kLink, t / 2, t));
      EXPECT_FALSE(interval_within_tolerance(t / 2, Counterpart::kLink, t / 2 * (1 + 1e-9), t));
    }
  }
}

// Every combination of the question at every tolerance class: a level allowed to decide errs by
// at most the tolerance, and is the largest that does; a motion walks down to the same level.
TEST(TolerancePolicy, EveryLevelAllowedToDecideFitsTheTolerance) {
  int deciding = 0;
  for (const Counterpart other : {Counterpart::kLink, Counterpart::kObject, Counterpart::kOctree}) {
    for (const double t : {0.0, 1e-4, 0.003, 0.01, 0.05}) {
      for (int bits = 0; bits < 16; ++bits) {
        ToleranceQuestion q{t, other};
        q.boolean = bits & 1, q.solids = bits & 2, q.motion = bits & 4, q.octree_field = bits & 8;
        const ProxyUse use = proxy_use(q);
        const bool exact = t == 0.0 || !q.boolean || !q.solids || (other == Counterpart::kOctree && !q.octree_field);
        if (exact) {
          EXPECT_EQ(use.decide_up_to, 0.0);
          continue;
        }
        ++deciding;
        EXPECT_LE(proxy_error(use.decide_up_to, other), t);
        EXPECT_GT(proxy_error(use.decide_up_to * (1 + 1e-12), other), t) << "not the largest level that fits";
      }
    }
  }
  // Four tolerances above 0; per counterpart the boolean questions on solids, state or motion,
  // with or without a field (the octree's only with it).
  EXPECT_EQ(deciding, 4 * (4 + 4 + 2));
}

// The demo arm's obstacles: a pillar of voxels (the octree), or a box and a cylinder (objects).
Environment demo_environment(bool octree) {
  Environment env(0.02);
  if (octree) {
    std::vector<ScanPoint> pillar;
    for (double x = 0.39; x <= 0.51 + 1e-9; x += 0.01) {
      for (double y = 0.29; y <= 0.41 + 1e-9; y += 0.01) {
        for (double z = 0.0; z <= 0.8 + 1e-9; z += 0.01) pillar.emplace_back(float(x), float(y), float(z));
      }
    }
    insert_points(env.octree(), pillar);
    return env;
  }
  env.add_object("shelf", ObjectShape::box(Vec3(0.5, 0.1, 0.04)), Transform::Translation(Vec3(-0.3, -0.35, 0.5)));
  env.add_object("post", ObjectShape::cylinder(0.04, 0.8), Transform::Translation(Vec3(-0.3, 0.35, 0.4)));
  return env;
}

// The exact distance from the robot to the environment (0 in collision).
double exact_distance(const CollisionChecker& checker, const double* q, const Environment& env) {
  EnvironmentRequest exact;
  exact.distance = true;
  exact.distance_field = EnvironmentRequest::DistanceField::kOff;
  const EnvironmentResult truth = checker.check_environment(q, env, exact);
  return truth.collision ? 0.0 : truth.min_distance;
}

// The level each tolerance class gets, and that every kind pair keeps the contract with it.
TEST(TolerancePolicy, EachToleranceClassKeepsTheContractOnEveryKindPair) {
  CheckerOptions options;
  options.proxy_levels = {0.005, 0.01, 0.02};
  options.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
  const CollisionChecker checker = test::demo_arm_checker(options);
  const Environment voxels = demo_environment(true);
  ASSERT_NE(checker.prepare_distance_field(voxels), nullptr);
  const auto objects = std::make_shared<const Environment>(demo_environment(false));
  struct Class {
    double tolerance, self_level, obstacle_level;  // the levels that may decide (0: none)
  };
  const Class classes[] = {{0.0, 0.0, 0.0}, {0.003, 0.0, 0.005}, {0.006, 0.005, 0.01}, {0.012, 0.01, 0.02}, {0.03, 0.02, 0.02}};
  std::mt19937_64 rng(41);
  int near_hits = 0;  // answers of collision at d > 0: the proxies decided
  for (const Class& c : classes) {
    const ProxyLevel* self = checker.accelerators().proxies_for(proxy_use({c.tolerance, Counterpart::kLink}).decide_up_to);
    ToleranceQuestion octree{c.tolerance, Counterpart::kOctree};
    octree.octree_field = true;
    const ProxyLevel* obstacle = checker.accelerators().proxies_for(proxy_use(octree).decide_up_to);
    EXPECT_EQ(self ? self->level : 0.0, c.self_level) << c.tolerance;
    EXPECT_EQ(obstacle ? obstacle->level : 0.0, c.obstacle_level) << c.tolerance;
    SceneCheckOptions scene_options;
    scene_options.tolerance = c.tolerance;
    scene_options.states_at_tolerance = true;
    scene_options.self = false;
    const SceneChecker against_objects(checker, objects, scene_options);
    for (int i = 0; i < test::sized(600); ++i) {
      const std::vector<double> q = random_configuration(checker.model(), rng);
      // Link x link.
      SelfCollisionRequest exact_self;
      exact_self.distance = true;
      const SelfCollisionResult ts = checker.check_self(q.data(), exact_self);
      const double ds = ts.collision ? 0.0 : ts.min_distance;
      SelfCollisionRequest self_request;
      self_request.tolerance = c.tolerance;
      const bool self_hit = checker.check_self(q.data(), self_request).collision;
      // Link x octree (its field kept).
      const double dv = exact_distance(checker, q.data(), voxels);
      EnvironmentRequest request;
      request.tolerance = c.tolerance;
      const bool voxel_hit = checker.check_environment(q.data(), voxels, request).collision;
      // Link x object.
      const double dobj = exact_distance(checker, q.data(), *objects);
      const bool object_hit = against_objects.collides(q.data());
      for (const auto& [kind, d, hit] : {std::tuple{"self", ds, self_hit}, std::tuple{"octree", dv, voxel_hit},
                                         std::tuple{"objects", dobj, object_hit}}) {
        if (d == 0.0) {
          ASSERT_TRUE(hit) << kind << ", tolerance " << c.tolerance << ", state " << i;
        }
        if (hit) {
          ASSERT_LE(d, c.tolerance + kRounding) << kind << ", tolerance " << c.tolerance << ", state " << i;
        }
        near_hits += hit && d > 0.0;
      }
    }
  }
  EXPECT_GT(near_hits, 0) << "no answer came from the proxies";
}

// With no proxy level to answer, a tolerance takes the exact path and never costs more than the
// exact answer: per state, the work of a check at 2, 5, 10 and 20 mm (shape pairs taken past the
// broad phase, volumes carried and tested, triangles tested) is at most that at 0, against the
// robot itself, objects and the octree, on the demo arm and panda. A tolerance used to widen the
// broad phase and the hull test, which only added pairs (each then walked to the padding): panda's
// self check took 2.09 us exact, 2.78 us at 10 mm and 3.14 us at 20 mm.
TEST(TolerancePolicy, ATolerancesWorkIsNeverMoreThanTheExactOnes) {
  auto work = [](const QueryStats& s) { return s.pair_tests + s.volume_updates + s.volume_tests + s.primitive_tests; };
  std::vector<CollisionChecker> checkers;
  checkers.push_back(test::demo_arm_checker());
  if (std::filesystem::is_directory(test::robots_dir())) checkers.push_back(test::panda_as_moveit());
  const Environment voxels = demo_environment(true), objects = demo_environment(false);
  std::mt19937_64 rng(43);
  std::uint64_t exact_work = 0, tolerant_work = 0;
  int hits = 0, states = 0;
  for (const CollisionChecker& checker : checkers) {
    ASSERT_TRUE(checker.accelerators().proxy_levels().empty());
    for (int i = 0; i < test::sized(300); ++i, ++states) {
      const std::vector<double> q = random_configuration(checker.model(), rng);
      const SelfCollisionResult self0 = checker.check_self(q.data(), SelfCollisionRequest{});
      EnvironmentRequest env0;
      const EnvironmentResult voxels0 = checker.check_environment(q.data(), voxels, env0);
      const EnvironmentResult objects0 = checker.check_environment(q.data(), objects, env0);
      hits += self0.collision + voxels0.collision + objects0.collision;
      for (const double t : {0.002, 0.005, 0.01, 0.02}) {
        const SelfCollisionResult self = checker.check_self(q.data(), SelfCollisionRequest{t});
        EnvironmentRequest env;
        env.tolerance = t;
        const EnvironmentResult v = checker.check_environment(q.data(), voxels, env), o = checker.check_environment(q.data(), objects, env);
        ASSERT_LE(work(self.stats), work(self0.stats)) << "self, state " << i << ", tolerance " << t;
        ASSERT_LE(work(v.stats), work(voxels0.stats)) << "octree, state " << i << ", tolerance " << t;
        ASSERT_LE(work(o.stats), work(objects0.stats)) << "objects, state " << i << ", tolerance " << t;
        ASSERT_TRUE(!self0.collision || self.collision) << "a collision missed at tolerance " << t;
        ASSERT_TRUE(!voxels0.collision || v.collision) << "a collision missed at tolerance " << t;
        ASSERT_TRUE(!objects0.collision || o.collision) << "a collision missed at tolerance " << t;
        exact_work += work(self0.stats) + work(voxels0.stats) + work(objects0.stats);
        tolerant_work += work(self.stats) + work(v.stats) + work(o.stats);
      }
    }
  }
  std::printf("%d states: work at a tolerance %.3f of the exact work, %d collisions\n", states,
              static_cast<double>(tolerant_work) / static_cast<double>(exact_work), hits);
  EXPECT_GT(hits, states / 20);
  EXPECT_GT(exact_work, 0u);
}

// A level answers a self pair only where the build measured it not slower than the exact test
// (model/proxy_calibration.h): a tolerance never costs. Whatever the timing decided, the answers
// follow the decision exactly: every pair the level leaves to the exact test is answered as the
// exact path answers it at that tolerance, every other as the proxies alone answer it, one state at
// a time and in the SIMD batch (which then runs the left pairs exactly for the states its lanes
// found free). Which pairs pay is a timing and not asserted; that a tolerance row is not slower
// than the exact one is the report's check (make bench).
TEST(TolerancePolicy, ALevelAnswersOnlyThePairsItWasMeasuredToPay) {
  using Make = CollisionChecker (*)(const CheckerOptions&);
  std::vector<std::pair<const char*, Make>> robots = {{"demo arm", test::demo_arm_checker}};
  if (std::filesystem::is_directory(test::robots_dir())) robots.emplace_back("panda", test::panda_as_moveit);
  std::mt19937_64 rng(44);
  for (const auto& [name, make] : robots) {
    for (const double level : {0.005, 0.02}) {
      CheckerOptions calibrated;
      calibrated.proxy_levels = {level};
      CheckerOptions forced = calibrated;
      forced.calibrate_proxies = false;
      const CollisionChecker mixed = make(calibrated), proxies = make(forced), exact = make(CheckerOptions{});
      const ProxyLevel& built = mixed.accelerators().proxy_levels().front();
      const std::size_t pairs = mixed.checked_pairs().size();
      ASSERT_EQ(built.pair_costs.size(), pairs);
      ASSERT_EQ(built.pair_exact.size(), pairs);
      std::size_t sampled = 0;
      std::vector<std::size_t> left;
      for (std::size_t p = 0; p < pairs; ++p) {
        const PairCost& c = built.pair_costs[p];
        if (c.samples > 0) {
          ++sampled;
          EXPECT_GT(c.exact_seconds, 0.0) << name << " pair " << p;
          EXPECT_GT(c.proxy_seconds, 0.0) << name << " pair " << p;
        }
        EXPECT_EQ(built.pair_exact[p] != 0, !c.proxies_pay()) << name << " pair " << p;
        if (built.pair_exact[p]) left.push_back(p);
      }
      EXPECT_EQ(built.exact_pairs, left);
      EXPECT_GT(sampled, 0u) << name;
      EXPECT_TRUE(proxies.accelerators().proxy_levels().front().exact_pairs.empty());
      std::printf("%s at %g mm: %zu of %zu pairs timed, %zu left to the exact test; level ready in %.3f s (from the cache, "
                  "the calibration included)\n", name, level * 1e3, sampled, pairs, left.size(), built.build_seconds);
      const int n = test::sized(200);
      std::vector<double> flat;
      std::vector<char> single;
      SelfCollisionRequest all{level};
      all.all_pairs = true;
      for (int i = 0; i < n; ++i) {
        const std::vector<double> q = random_configuration(mixed.model(), rng);
        flat.insert(flat.end(), q.begin(), q.end());
        const SelfCollisionResult m = mixed.check_self(q.data(), all);
        const SelfCollisionResult x = exact.check_self(q.data(), all), y = proxies.check_self(q.data(), all);
        for (std::size_t p = 0; p < pairs; ++p) {
          const auto named = [&](const SelfCollisionResult& r) {
            return std::find(r.colliding_pairs.begin(), r.colliding_pairs.end(), mixed.checked_pairs()[p]) != r.colliding_pairs.end();
          };
          ASSERT_EQ(named(m), named(built.pair_exact[p] ? x : y)) << name << " state " << i << " pair " << p;
        }
        single.push_back(mixed.check_self(q.data(), SelfCollisionRequest{level}).collision);
      }
      BatchRequest batch;
      batch.environment = false;
      batch.tolerance = level;
      EXPECT_EQ(mixed.check_batch(flat.data(), static_cast<std::size_t>(n), nullptr, batch), single) << name;
    }
  }
}

}  // namespace
}  // namespace bvh_collision
