// The vectorised batch of proxy self checks (model/proxy_batch.h) against independent oracles:
// its sine and cosine against the C library, its forward kinematics against KinematicsPlan on
// every joint kind, and its answers against the one-state proxy check (the same decision, state
// by state), the exact check (no false negative; every collision within padding + level) and
// each other: the SSE2 and the AVX2 build answer alike, bit for bit where they compute values.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/sin_cos.h"
#include "bvh_collision/robot/package_resolver.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

// Every kernel this CPU runs. The test machine has AVX2 (CI runs there); a CPU without it runs
// the SSE2 build alone, and says so.
std::vector<SimdPath> kernels() {
  if (avx2_available()) return {SimdPath::kGeneric, SimdPath::kAvx2};
  std::printf("this CPU has no AVX2: the SSE2 kernel only\n");
  return {SimdPath::kGeneric};
}

CollisionChecker demo_checker(const CheckerOptions& options) {
  RobotModel m = RobotModel::from_urdf(*load_robot_description_file(test::source_dir() + "/urdf/demo_arm.urdf"),
                                       PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(m);
  return CollisionChecker(std::move(m), std::move(acm), options);
}

TEST(ProxyBatch, SineAndCosineMatchTheCLibraryAndTheOneValueForm) {
  std::mt19937_64 rng(3);
  std::vector<double> xs = {0.0, -0.0, M_PI / 4, -M_PI / 4, M_PI / 2, M_PI, 1.5 * M_PI, 2 * M_PI, 1e-300, 5e-324,
                            1.6e6, -1.6e6, 1.7e6, 1e22, std::numeric_limits<double>::infinity(),
                            -std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()};
  // Around every multiple of pi/4 up to 1e6 (where the reduction cancels most), and uniform.
  for (int i = 0; i < test::sized(40000); ++i) {
    const double k = std::floor(std::uniform_real_distribution<double>(-1.27e6, 1.27e6)(rng));
    xs.push_back(k * M_PI / 4 + std::uniform_real_distribution<double>(-1e-6, 1e-6)(rng));
    xs.push_back(std::uniform_real_distribution<double>(-7.0, 7.0)(rng));
    xs.push_back(std::uniform_real_distribution<double>(-1.6e6, 1.6e6)(rng));
  }
  while (xs.size() % 4 != 0) xs.push_back(1.0);
  double worst = 0.0;
  for (std::size_t i = 0; i < xs.size(); i += 4) {
    double s[2][4], c[2][4];
    const std::vector<SimdPath> paths = kernels();
    for (std::size_t p = 0; p < paths.size(); ++p) ProxyBatch::sincos(&xs[i], s[p], c[p], paths[p]);
    for (int l = 0; l < 4; ++l) {
      const double x = xs[i + l];
      if (paths.size() == 2) {
        ASSERT_EQ(std::memcmp(&s[0][l], &s[1][l], sizeof(double)), 0) << x;
        ASSERT_EQ(std::memcmp(&c[0][l], &c[1][l], sizeof(double)), 0) << x;
      }
      // The one-value form (geometry/sin_cos.h, KinematicsPlan's) gives the lanes' bits.
      double one_s = 0.0, one_c = 0.0;
      sin_cos(x, one_s, one_c);
      ASSERT_EQ(std::memcmp(&s[0][l], &one_s, sizeof(double)), 0) << x;
      ASSERT_EQ(std::memcmp(&c[0][l], &one_c, sizeof(double)), 0) << x;
      if (!std::isfinite(x)) {
        EXPECT_TRUE(std::isnan(s[0][l]) && std::isnan(c[0][l])) << x;
        continue;
      }
      // The C library is within an ulp of exact; the kernel claims 1e-15 (proxy_batch_kernel.h).
      const double err = std::max(std::abs(s[0][l] - std::sin(x)), std::abs(c[0][l] - std::cos(x)));
      worst = std::max(worst, err);
      ASSERT_LE(err, 1e-15) << "x = " << x;
    }
  }
  std::printf("%zu arguments: largest difference from the C library %.2e\n", xs.size(), worst);
}

// One link per joint kind the kernel computes: revolute about a general axis, prismatic along a
// general axis, continuous about -z, a mimic, a fixed joint with a rotated origin, a floating
// joint (at identity, as self checks take it).
const char* kJointKinds = R"(<robot name="kinds">
  <link name="base"><collision><geometry><box size="0.1 0.1 0.1"/></geometry></collision></link>
  <link name="a"><collision><geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="b"><collision><geometry><box size="0.05 0.2 0.05"/></geometry></collision></link>
  <link name="c"><collision><geometry><cylinder radius="0.03" length="0.2"/></geometry></collision></link>
  <link name="d"><collision><geometry><sphere radius="0.04"/></geometry></collision></link>
  <link name="e"><collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision></link>
  <link name="f"><collision><geometry><sphere radius="0.02"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0.1 0.2 0.3" rpy="0.3 -0.2 0.9"/><axis xyz="0.6 0.8 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="prismatic"><parent link="a"/><child link="b"/>
    <origin xyz="0 0 0.2" rpy="0 0.5 0"/><axis xyz="0 0.6 0.8"/>
    <limit lower="-0.4" upper="0.4" effort="1" velocity="1"/></joint>
  <joint name="j3" type="continuous"><parent link="b"/><child link="c"/>
    <origin xyz="0.1 0 0.1" rpy="1.2 0 0"/><axis xyz="0 0 -1"/></joint>
  <joint name="j4" type="revolute"><parent link="c"/><child link="d"/>
    <origin xyz="0 0.1 0" rpy="0 0 0"/><axis xyz="1 0 0"/>
    <mimic joint="j1" multiplier="-0.5" offset="0.25"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j5" type="fixed"><parent link="d"/><child link="e"/>
    <origin xyz="0.05 0.05 0.05" rpy="0.1 0.2 0.3"/></joint>
  <joint name="j6" type="floating"><parent link="base"/><child link="f"/>
    <origin xyz="0.5 0 0" rpy="0 0 0"/></joint>
</robot>)";

void expect_poses_match(const CollisionChecker& c, int states, std::uint64_t seed) {
  const RobotCollisionModel& m = c.collision_model();
  const ProxyBatch batch(m, PairClearance{}, ProxyLevel{});  // kinematics only: no proxy spheres
  std::mt19937_64 rng(seed);
  for (int i = 0; i < states; ++i) {
    std::vector<double> four;
    for (int l = 0; l < 4; ++l) {
      std::vector<double> q = random_configuration(c.model(), rng);
      // Continuous joints several turns out, as planners send them.
      for (double& v : q) v += 2 * M_PI * std::uniform_int_distribution<int>(-2, 2)(rng) * (l == 3);
      four.insert(four.end(), q.begin(), q.end());
    }
    std::vector<std::vector<double>> got;
    for (const SimdPath p : kernels()) got.push_back(batch.poses(four.data(), 4, p));
    if (got.size() == 2) {
      ASSERT_EQ(got[0], got[1]) << "the SSE2 and AVX2 kernels computed different poses";
    }
    for (int l = 0; l < 4; ++l) {
      std::vector<Transform> poses;
      m.kinematics().compute(four.data() + l * c.model().variable_count(), poses);
      for (std::size_t link = 0; link < poses.size(); ++link) {
        if (m.bounds()[link].radius < 0) continue;  // links without geometry need no pose
        for (int e = 0; e < 12; ++e) {
          const double want = e < 9 ? poses[link].R(e / 3, e % 3) : poses[link].t[e - 9];
          ASSERT_NEAR(got[0][(link * 12 + e) * 4 + l], want, 1e-12)
              << c.model().links()[link].name << " element " << e << " lane " << l;
        }
      }
    }
  }
}

TEST(ProxyBatch, PosesEqualTheKinematicsPlanOnEveryJointKind) {
  CheckerOptions o;
  o.pair_clearance_cells = 0;
  RobotModel m = RobotModel::from_urdf(*parse_robot_description(kJointKinds), PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(m);
  const CollisionChecker kinds(std::move(m), std::move(acm), o);
  expect_poses_match(kinds, test::sized(400), 5);
  expect_poses_match(demo_checker(o), test::sized(200), 6);
  BVH_REQUIRE_ROBOTS();
  for (const char* robot : {"panda", "ur5e", "pr2"}) expect_poses_match(test::load_checker(robot, o), test::sized(100), 7);
}

// The batch's answers, state by state, against the one-state proxy check (the same decision)
// and the exact check (the contract), on uniform states and near-contact ones.
void expect_batch_keeps_the_contract(const CollisionChecker& exact, const CollisionChecker& proxied, double tolerance,
                                     int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const std::size_t n = exact.model().variable_count();
  std::vector<double> flat;
  for (int i = 0; i < count; ++i) {
    std::vector<double> q = random_configuration(exact.model(), rng);
    flat.insert(flat.end(), q.begin(), q.end());
  }
  const std::size_t states = flat.size() / n;
  std::vector<std::vector<char>> answers;
  for (const SimdPath p : kernels()) {
    BatchRequest request;
    request.environment = false;
    request.tolerance = tolerance;
    request.simd = p;
    answers.push_back(proxied.check_batch(flat.data(), states, nullptr, request));
  }
  if (answers.size() == 2) {
    ASSERT_EQ(answers[0], answers[1]) << "the SSE2 and AVX2 kernels disagree";
  }
  int collide = 0, false_positives = 0, near = 0;
  const double padding = 2 * exact.link_padding(0);
  for (std::size_t i = 0; i < states; ++i) {
    const double* q = flat.data() + i * n;
    SelfCollisionRequest at;
    at.tolerance = tolerance;
    ASSERT_EQ(answers[0][i] != 0, proxied.check_self(q, at).collision) << "state " << i << ": not the one-state answer";
    SelfCollisionRequest request;
    request.distance = true;
    const SelfCollisionResult truth = exact.check_self(q, request);
    const double d = truth.collision ? 0.0 : truth.min_distance;
    collide += truth.collision;
    near += !truth.collision && d < 0.04;
    if (truth.collision) {
      ASSERT_TRUE(answers[0][i]) << "a false negative, state " << i;
    }
    if (answers[0][i]) {
      ASSERT_LE(d, padding + tolerance + 1e-9) << "state " << i;
    }
    false_positives += answers[0][i] && !truth.collision;
  }
  EXPECT_GT(collide, count / 20);
  EXPECT_GT(near, count / 50);
  std::printf("%s at %.0f mm, padding %.3f: %zu states, %d colliding, %d within 4 cm, %d false positives\n",
              exact.model().name().c_str(), tolerance * 1e3, padding / 2, states, collide, near, false_positives);
}

TEST(ProxyBatch, DemoArmBatchKeepsTheContract) {
  for (const double padding : {0.0, 0.01}) {
    CheckerOptions e, p;
    e.padding = p.padding = padding;
    p.proxy_levels = {0.02};
    p.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
    // At a tolerance above the level too: the broad phase then reaches farther, as check_self's.
    for (const double tolerance : {0.02, 0.05}) {
      expect_batch_keeps_the_contract(demo_checker(e), demo_checker(p), tolerance, test::sized(2000), 21);
    }
  }
}

TEST(ProxyBatch, PandaAndUr5eBatchesKeepTheContract) {
  BVH_REQUIRE_ROBOTS();
  if (test::sanitized()) {
    // Their proxies take minutes to build under the sanitizers; the demo arm runs there.
    std::printf("under the sanitizers: the demo arm's test only\n");
    return;
  }
  for (const char* robot : {"panda", "ur5e"}) {
    CheckerOptions e, p;
    e.padding = p.padding = 0.002;
    p.proxy_levels = {0.01};
    p.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
    expect_batch_keeps_the_contract(test::load_checker(robot, e), test::load_checker(robot, p), 0.01, 3000, 22);
  }
}

// Batches of every length around the lane count (the last block repeats its last state), and
// the batch at a tolerance below every level (the exact path).
TEST(ProxyBatch, EveryBatchLengthAndTheExactPath) {
  CheckerOptions p;
  p.proxy_levels = {0.02};
  p.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
  const CollisionChecker c = demo_checker(p);
  std::mt19937_64 rng(9);
  std::vector<double> flat;
  for (int i = 0; i < 64; ++i) {
    const std::vector<double> q = random_configuration(c.model(), rng);
    flat.insert(flat.end(), q.begin(), q.end());
  }
  for (std::size_t count = 0; count <= 9; ++count) {
    for (const double tolerance : {0.0, 0.02}) {
      BatchRequest request;
      request.environment = false;
      request.tolerance = tolerance;
      const std::vector<char> got = c.check_batch(flat.data(), count, nullptr, request);
      ASSERT_EQ(got.size(), count);
      for (std::size_t i = 0; i < count; ++i) {
        SelfCollisionRequest one;
        one.tolerance = tolerance;
        EXPECT_EQ(got[i] != 0, c.check_self(flat.data() + i * c.model().variable_count(), one).collision)
            << count << " states, state " << i << ", tolerance " << tolerance;
      }
    }
  }
}

// A fixed-step motion at a tolerance a level fits checks its states in blocks of lanes: its
// answer (valid, states checked, last valid fraction) is that of the states one at a time.
TEST(ProxyBatch, FixedStepMotionsAnswerAsStateByState) {
  CheckerOptions p;
  p.proxy_levels = {0.02};
  p.calibrate_proxies = false;  // the proxies answer every pair: their contract is tested
  const CollisionChecker c = demo_checker(p);
  const Environment empty(0.02);
  std::mt19937_64 rng(13);
  int valid = 0;
  for (int m = 0; m < test::sized(200); ++m) {
    const std::vector<double> a = random_configuration(c.model(), rng), b = random_configuration(c.model(), rng);
    MotionRequest request;
    request.environment = false;
    request.tolerance = 0.02;
    request.resolution = std::uniform_real_distribution<double>(0.005, 0.1)(rng);
    const MotionResult got = c.check_motion(a.data(), b.data(), empty, request);
    double longest = 0.0;
    for (std::size_t j = 0; j < a.size(); ++j) longest = std::max(longest, std::abs(b[j] - a[j]));
    const auto steps = static_cast<std::size_t>(std::max(1.0, std::ceil(longest / request.resolution)));
    std::size_t checked = 0;
    double last = 0.0;
    bool free = true;
    for (std::size_t i = 0; i <= steps && free; ++i) {
      const double s = static_cast<double>(i) / static_cast<double>(steps);
      std::vector<double> q(a.size());
      for (std::size_t j = 0; j < a.size(); ++j) q[j] = s >= 1.0 ? b[j] : a[j] + s * (b[j] - a[j]);
      ++checked;
      SelfCollisionRequest one;
      one.tolerance = 0.02;
      free = !c.check_self(q.data(), one).collision;
      if (free) last = s;
    }
    ASSERT_EQ(got.valid, free) << "motion " << m;
    ASSERT_EQ(got.states_checked, checked) << "motion " << m;
    ASSERT_EQ(got.last_valid_fraction, last) << "motion " << m;
    valid += free;
  }
  EXPECT_GT(valid, 0);
  EXPECT_LT(valid, test::sized(200));
}

}  // namespace
}  // namespace bvh_collision
