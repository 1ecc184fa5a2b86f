// The link proxies in every query kind (issue 18, point 2), each against the exact answer:
// proxy distances as clearance lower bounds (pairs and whole states), certified motions at a
// tolerance, boolean environment checks against the octree and objects, and the self filter.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <random>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/octree/distance_field.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

constexpr double kRounding = 1e-9;
// Under the sanitizers (about ten times slower, looking for memory errors rather than rarer
// geometry) one robot, level and padding per test instead of several.
const bool kFew = test::sanitized();

std::mt19937_64& rng() {
  static std::mt19937_64 r(181);
  return r;
}

CollisionChecker demo_checker(double padding, std::vector<double> levels) {
  CheckerOptions options;
  options.padding = padding;
  options.proxy_levels = std::move(levels);
  options.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
  return test::demo_arm_checker(options);
}

// The demo's pillar (a 12 x 12 x 80 cm box's surface in a 2 cm octree), a box lying across the
// arm's reach and a bumpy mesh ball: every obstacle kind the environment has.
Environment demo_environment() {
  Environment env(0.02);
  std::vector<ScanPoint> pillar;
  for (double x = 0.39; x <= 0.51 + 1e-9; x += 0.01) {
    for (double y = 0.29; y <= 0.41 + 1e-9; y += 0.01) {
      for (double z = 0.0; z <= 0.8 + 1e-9; z += 0.01) pillar.emplace_back(float(x), float(y), float(z));
    }
  }
  insert_points(env.octree(), pillar);
  env.add_object("shelf", ObjectShape::box(Vec3(0.5, 0.1, 0.04)), Transform::Translation(Vec3(-0.3, -0.35, 0.5)));
  env.add_object("blob", ObjectShape::triangles(test::bumpy_sphere(rng(), 0.08, 8, 10, 0.1)),
                 Transform::Translation(Vec3(0.0, 0.45, 0.6)));
  return env;
}

// The exact clearance of a state: its smallest distance less padding, self pairs (both links'
// padding) and links against every obstacle (the link's), as certified motions define it.
double exact_clearance(const CollisionChecker& checker, const double* q, const Environment& env, double padding) {
  SelfCollisionRequest self;
  self.distance = true;
  const SelfCollisionResult s = checker.check_self(q, self);
  EnvironmentRequest environment;
  environment.distance = true;
  environment.distance_field = EnvironmentRequest::DistanceField::kOff;
  const EnvironmentResult e = checker.check_environment(q, env, environment);
  // A collision within the padding still has its distance (0 for touching or overlapping).
  const double self_gap = s.min_distance - 2 * padding;
  const double env_gap = e.min_distance - padding;
  return std::min(self_gap, env_gap);
}

// Per checked pair of panda and ur5e: no slack, the bound lies between the exact distance less
// both proxies' Hausdorff bounds and the exact distance; with a slack, it stays a lower bound, is
// at least the exact bound over 1 + slack, and is the exact bound where at most exact_below.
TEST(ProxiesDistance, BoundsEveryPairWithinTheLevels) {
  BVH_REQUIRE_ROBOTS();
  for (const std::string robot : {"panda", "ur5e"}) {
    if (kFew && robot != "panda") continue;
    CheckerOptions options;
    options.proxy_levels = {0.02};
    options.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
    const CollisionChecker checker = test::load_checker(robot, options);
    const RobotCollisionModel& model = checker.collision_model();
    std::size_t compared = 0, slack_differs = 0;
    for (int i = 0; i < test::sized(60); ++i) {
      const std::vector<double> q = random_configuration(checker.model(), rng());
      std::vector<Transform> poses;
      model.kinematics().compute(q.data(), poses);
      for (std::size_t p = 0; p < checker.checked_pairs().size(); ++p) {
        const auto [a, b] = checker.checked_pairs()[p];
        SelfCollisionRequest exact;
        exact.distance = true;
        const std::vector<std::size_t> only = {p};
        exact.only_pairs = &only;
        const SelfCollisionResult r = checker.check_self(q.data(), exact);
        const double d = r.collision ? 0.0 : r.min_distance;
        for (const ProxyLevel& level : checker.accelerators().proxy_levels()) {
          const LinkProxy& pa = level.links[a];
          const LinkProxy& pb = level.links[b];
          const double bound = proxies_distance(pa, poses[a], pb, poses[b], 1e9);
          ASSERT_LE(bound, d + kRounding) << robot << " pair " << p << " state " << i;
          ASSERT_GE(bound, d - pa.hausdorff_bound() - pb.hausdorff_bound() - kRounding) << robot << " pair " << p;
          const ProxySlack slack{0.25, 0.02};
          const double loose = proxies_distance(pa, poses[a], pb, poses[b], 1e9, slack);
          ASSERT_LE(loose, bound + kRounding);
          ASSERT_GE(loose, bound / 1.25 - kRounding);
          if (loose <= slack.exact_below) {
            ASSERT_NEAR(loose, bound, kRounding);
          }
          slack_differs += loose < bound - 1e-6;
          ++compared;
        }
      }
    }
    EXPECT_GT(compared, 100u);
    EXPECT_GT(slack_differs, 0u) << robot << ": the slack never left a pair unopened";
  }
}

// Certified motions at 10 and 20 mm: a motion found valid has no colliding state on a dense
// sweep of exact checks; one found colliding has an exact clearance within the tolerance at the
// state it names; and the proxies did the work (fewer exact-equal answers than states).
TEST(CertifiedMotion, AtAToleranceKeepsTheContract) {
  const Environment env = demo_environment();
  // (Under the sanitizers without the 5 mm level: its build is most of the test's time there.)
  const CollisionChecker checker = demo_checker(0.0, kFew ? std::vector<double>{0.01, 0.02} : std::vector<double>{0.005, 0.01, 0.02});
  checker.prepare_distance_field(env);
  const std::size_t n = checker.model().variable_count();
  int valid = 0, colliding = 0;
  for (int m = 0; m < test::sized(40); ++m) {
    const std::vector<double> a = random_configuration(checker.model(), rng());
    const std::vector<double> b = random_configuration(checker.model(), rng());
    for (const double tolerance : {0.01, 0.02}) {
      MotionRequest request;
      request.tolerance = tolerance;
      const MotionResult r = checker.check_motion(a.data(), b.data(), env, request);
      ASSERT_TRUE(r.certified) << r.message;
      std::vector<double> q(n);
      if (r.valid) {
        ++valid;
        for (int k = 0; k <= 400; ++k) {
          for (std::size_t j = 0; j < n; ++j) q[j] = a[j] + (b[j] - a[j]) * k / 400.0;
          ASSERT_FALSE(checker.check_self(q.data()).collision) << "motion " << m << " sample " << k;
          EnvironmentRequest exact;
          exact.distance_field = EnvironmentRequest::DistanceField::kOff;
          ASSERT_FALSE(checker.check_environment(q.data(), env, exact).collision) << "motion " << m << " sample " << k;
        }
      } else {
        ++colliding;
        ASSERT_GE(r.colliding_fraction, r.last_valid_fraction);
        for (std::size_t j = 0; j < n; ++j) q[j] = a[j] + (b[j] - a[j]) * std::min(1.0, r.colliding_fraction);
        // The motion comes within the tolerance of a collision (the engine names the middle of the
        // interval where it does): a sweep of exact clearances finds it, to within what the links
        // can move between two of its states.
        constexpr int kSweep = 2000;
        double speed = 0.0;
        for (std::size_t l = 0; l < checker.model().links().size(); ++l) speed = std::max(speed, checker.link_speed(static_cast<int>(l), a.data(), b.data()));
        double least = std::numeric_limits<double>::infinity();
        for (int k = 0; k <= kSweep && least > tolerance; ++k) {
          for (std::size_t j = 0; j < n; ++j) q[j] = a[j] + (b[j] - a[j]) * k / double(kSweep);
          least = std::min(least, exact_clearance(checker, q.data(), env, 0.0));
        }
        ASSERT_LE(least, tolerance + speed / kSweep + kRounding) << "motion " << m;
      }
    }
  }
  EXPECT_GT(valid, 0);
  EXPECT_GT(colliding, 0);
}

// Boolean environment checks at a tolerance answer from the proxies once the distance field is
// kept: never a false negative, every collision (and every contact) within padding + tolerance
// of the exact distance, and some false positives (else the proxies were not used).
TEST(EnvironmentProxies, NoFalseNegativeAndHitsWithinTheTolerance) {
  BVH_REQUIRE_ROBOTS();
  Environment env(0.02);
  std::vector<ScanPoint> table;
  for (double x = 0.3; x <= 0.9; x += 0.01) {
    for (double y = -0.5; y <= 0.5; y += 0.01) table.emplace_back(float(x), float(y), 0.3f);
  }
  for (double z = 0.3; z <= 0.6; z += 0.01) {
    for (double y = -0.1; y <= 0.1; y += 0.01) table.emplace_back(0.5f, float(y), float(z));
  }
  insert_points(env.octree(), table);
  env.add_object("post", ObjectShape::cylinder(0.04, 0.8), Transform::Translation(Vec3(-0.4, 0.3, 0.4)));
  env.add_object("blob", ObjectShape::triangles(test::bumpy_sphere(rng(), 0.1, 8, 10, 0.1)),
                 Transform::Translation(Vec3(0.0, -0.5, 0.5)));
  int false_positives = 0;  // over every case: each alone may have none in a small sample
  for (const double padding : {0.0, 0.01}) {
    if (kFew && padding == 0.0) continue;
    CheckerOptions options;
    options.padding = padding;
    options.proxy_levels = kFew ? std::vector<double>{0.02} : std::vector<double>{0.01, 0.02};
    options.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
    const CollisionChecker checker = test::load_checker("panda", options);
    ASSERT_NE(checker.prepare_distance_field(env), nullptr);
    for (const double tolerance : {0.005, 0.01}) {
      int hits = 0;
      for (int i = 0; i < test::sized(800); ++i) {
        const std::vector<double> q = random_configuration(checker.model(), rng());
        EnvironmentRequest exact;
        exact.distance = true;
        exact.all_links = true;
        exact.distance_field = EnvironmentRequest::DistanceField::kOff;
        const EnvironmentResult truth = checker.check_environment(q.data(), env, exact);
        const double d = truth.collision ? 0.0 : truth.min_distance;
        EnvironmentRequest request;
        request.tolerance = tolerance;
        request.all_links = i % 2 == 0;
        const EnvironmentResult r = checker.check_environment(q.data(), env, request);
        EnvironmentRequest boolean = request;  // as check_batch asks: the field's grid may answer alone
        boolean.contacts = false;
        ASSERT_EQ(checker.check_environment(q.data(), env, boolean).collision, r.collision) << "state " << i;
        if (d <= padding) {
          ASSERT_TRUE(r.collision) << "state " << i << " distance " << d;
        }
        if (r.collision) {
          ASSERT_LE(d, padding + tolerance + kRounding) << "state " << i;
          ++hits;
          false_positives += d > padding;
        }
        for (const EnvironmentContact& c : r.contacts) {
          // Each contact's link is itself within padding + tolerance of some obstacle.
          EnvironmentRequest one = exact;
          std::vector<char> only(checker.model().links().size(), 0);
          only[c.link] = 1;
          one.only_links = &only;
          const EnvironmentResult link = checker.check_environment(q.data(), env, one);
          ASSERT_LE(link.collision ? 0.0 : link.min_distance, padding + tolerance + kRounding) << "contact link " << c.link;
        }
      }
      EXPECT_GT(hits, 0) << "padding " << padding << " tolerance " << tolerance;
    }
  }
  EXPECT_GT(false_positives, 0) << "no false positive at all: the proxies were not used";
}

// The self filter with proxies built settles points sooner and answers exactly as without: the
// same points on the robot, shadowed and kept, for paddings that let the proxies accept (2 cm)
// or only reject (3 mm, 0).
TEST(SelfFilterProxies, SamePointsAsTheExactFilter) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker exact = test::load_checker("panda");
  CheckerOptions options;
  options.proxy_levels = {0.02};
  options.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
  const CollisionChecker proxied = test::load_checker("panda", options);
  std::uniform_real_distribution<double> offset(-0.05, 0.05);
  for (int round = 0; round < 4; ++round) {
    const std::vector<double> q = random_configuration(exact.model(), rng());
    std::vector<Transform> poses;
    forward_kinematics(exact.model(), q.data(), poses);
    std::vector<ScanPoint> points;
    for (std::size_t l = 0; l < poses.size(); ++l) {
      for (const CollisionElement& e : exact.model().links()[l].collision) {
        if (!e.mesh) continue;
        for (std::size_t v = 0; v < e.mesh->vertices.size(); v += 7) {
          const Vec3 p = poses[l] * (e.origin * e.mesh->vertices[v]) + Vec3(offset(rng()), offset(rng()), offset(rng()));
          points.push_back(p.cast<float>());
        }
      }
    }
    const ScanPoint sensor(1.5f, 0.2f, 1.2f);
    for (const double padding : {0.02, 0.003, 0.0}) {
      const FilteredScan a = exact.filter_scan(q.data(), points, sensor, padding);
      const FilteredScan b = proxied.filter_scan(q.data(), points, sensor, padding);
      ASSERT_EQ(a.on_robot, b.on_robot) << "padding " << padding;
      ASSERT_EQ(a.shadowed, b.shadowed);
      ASSERT_EQ(a.obstacles.size(), b.obstacles.size());
      for (std::size_t i = 0; i < a.obstacles.size(); ++i) {
        ASSERT_EQ(a.obstacles[i], b.obstacles[i]) << i;
      }
      ASSERT_EQ(a.clear_only.size(), b.clear_only.size());
      EXPECT_GT(a.on_robot, points.size() / 10) << "too few points near the robot to test";
    }
  }
}

// A level added to a built checker (how the node builds its levels after start-up) answers as
// one built at construction; the original is unchanged; levels stay finest first; a set cancel
// flag stops the build.
TEST(ProxyLevels, AddedLaterAnswerAsBuiltAtConstruction) {
  const CollisionChecker plain = demo_checker(0.0, {});
  const CollisionChecker built = demo_checker(0.0, {0.02});
  const CollisionChecker later = plain.with_proxy_level(0.02);
  EXPECT_TRUE(plain.accelerators().proxy_levels().empty());
  ASSERT_EQ(later.accelerators().proxy_levels().size(), 1u);
  const CollisionChecker both = later.with_proxy_level(0.01);
  ASSERT_EQ(both.accelerators().proxy_levels().size(), 2u);
  EXPECT_EQ(both.accelerators().proxy_levels()[0].level, 0.01);
  EXPECT_EQ(both.accelerators().proxy_levels()[1].level, 0.02);
  const std::size_t n = plain.model().variable_count();
  std::vector<double> flat;
  int hits = 0;
  for (int i = 0; i < test::sized(2000); ++i) {
    const std::vector<double> q = random_configuration(plain.model(), rng());
    flat.insert(flat.end(), q.begin(), q.end());
    const bool a = built.check_self(q.data(), SelfCollisionRequest{0.02}).collision;
    ASSERT_EQ(later.check_self(q.data(), SelfCollisionRequest{0.02}).collision, a) << "state " << i;
    hits += a;
  }
  EXPECT_GT(hits, 0);
  BatchRequest batch;
  batch.environment = false;
  batch.tolerance = 0.02;
  EXPECT_EQ(later.check_batch(flat.data(), flat.size() / n, nullptr, batch),
            built.check_batch(flat.data(), flat.size() / n, nullptr, batch));
  std::atomic<bool> cancel{true};
  EXPECT_THROW(plain.with_proxy_level(0.01, &cancel), ProxyBuildCancelled);
}

}  // namespace
}  // namespace bvh_collision
