// Motion checks and ray casts of CollisionChecker: the motion-rate bound against forward
// kinematics of every vertex; stepped motions against one check per state; certified motions
// against a dense sweep (never a missed collision, a thin obstacle a coarse step misses); rays
// against brute force over every link and object triangle, sphere and occupied voxel.
#include <gtest/gtest.h>

#include <iostream>
#include <random>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/octree/scan.h"
#include "bvh_collision/robot/robot_description.h"
#include "mesh_fixtures.h"
#include "checker_fixtures.h"
#include "robot_data.h"
#include "advancement_oracle.h"

namespace bvh_collision {
namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(23);
  return r;
}

// Every collision vertex of every link, in the world, for a state.
std::vector<std::vector<Vec3>> link_vertices(const RobotModel& model, const std::vector<double>& state) {
  std::vector<Transform> poses;
  forward_kinematics(model, state.data(), poses);
  std::vector<std::vector<Vec3>> out(poses.size());
  for (std::size_t l = 0; l < poses.size(); ++l) {
    for (const CollisionElement& e : model.links()[l].collision) {
      if (!e.mesh) continue;
      for (const Vec3& v : e.mesh->vertices) out[l].push_back(poses[l] * (e.origin * v));
    }
  }
  return out;
}

TEST(MotionRates, BoundEveryVertexDisplacement) {
  BVH_REQUIRE_ROBOTS();
  // Under the sanitizers panda only: loading ur5e and pr2 there is most of the test's time.
  const std::vector<std::string> robots = test::sanitized() ? std::vector<std::string>{"panda"}
                                                            : std::vector<std::string>{"panda", "ur5e", "pr2"};
  for (const std::string& robot : robots) {
    const CollisionChecker checker = test::load_checker(robot);
    const RobotModel& model = checker.model();
    std::uniform_real_distribution<double> step(-0.05, 0.05);
    double tightest = 0.0;
    for (int i = 0; i < 40; ++i) {
      const std::vector<double> q = random_configuration(model, rng());
      std::vector<double> q2 = q;
      for (double& v : q2) v += step(rng());
      const auto a = link_vertices(model, q), b = link_vertices(model, q2);
      for (std::size_t l = 0; l < a.size(); ++l) {
        if (a[l].empty()) continue;
        double bound = 0.0;
        for (std::size_t j = 0; j < q.size(); ++j) bound += checker.motion_rates(static_cast<int>(l))[j] * std::abs(q2[j] - q[j]);
        for (std::size_t k = 0; k < a[l].size(); ++k) {
          const double moved = (b[l][k] - a[l][k]).norm();
          // A straight joint move traces an arc at least as long as the chord.
          ASSERT_LE(moved, bound + 1e-12) << robot << " link " << model.links()[l].name;
          if (bound > 0) tightest = std::max(tightest, moved / bound);
        }
      }
    }
    EXPECT_GT(tightest, 0.1) << robot << ": the bound is valid but uselessly loose";
  }
}

// A slide (prismatic, 0..0.1 m) carrying a turntable whose arm reaches 0.3 m, and a mimic
// slide (twice the first, its own limits only 0..0.05 m) carrying a wrist: the rates assume joints
// within limits, and a request may hold values outside them ("say so, still answer").
constexpr const char* kSlideUrdf = R"(<robot name="slide">
  <link name="base"/>
  <link name="carriage"><collision><geometry><box size="0.05 0.05 0.05"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0.3 0 0"/><geometry><box size="0.1 0.02 0.02"/></geometry></collision></link>
  <link name="finger"/>
  <link name="tip"><collision><origin xyz="0 0.2 0"/><geometry><box size="0.02 0.1 0.02"/></geometry></collision></link>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="carriage"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.1" effort="1" velocity="1"/></joint>
  <joint name="turn" type="revolute"><parent link="carriage"/><child link="arm"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="finger_slide" type="prismatic"><parent link="arm"/><child link="finger"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.05" effort="1" velocity="1"/><mimic joint="slide" multiplier="2"/></joint>
  <joint name="wrist" type="revolute"><parent link="finger"/><child link="tip"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>)";

// The bound on how far a link's points move along a segment holds for states outside the joint
// limits and for a mimic slide whose own limits are narrower than its source's travel.
TEST(MotionRates, BoundHoldsOutsideLimitsAndForMimicSlides) {
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(kSlideUrdf), PackageResolver({}));
  AllowedCollisionMatrix acm(model.links().size());
  const CollisionChecker checker(std::move(model), std::move(acm));
  const RobotModel& m = checker.model();
  ASSERT_EQ(m.variable_count(), 3u);
  std::uniform_real_distribution<double> slide(-2.0, 2.0), angle(-3.0, 3.0);
  const std::size_t s = std::find(m.variable_names().begin(), m.variable_names().end(), "slide") - m.variable_names().begin();
  int outside = 0;
  for (int i = 0; i < 400; ++i) {
    std::vector<double> start(3), goal(3);
    for (std::size_t j = 0; j < 3; ++j) {
      start[j] = j == s ? slide(rng()) : angle(rng());
      goal[j] = i % 2 == 0 && j == s ? start[j] : (j == s ? slide(rng()) : angle(rng()));
    }
    if (i % 4 == 1) {
      // Within limits, at the far end, the wrist holding the tip straight out: only the turn
      // moves, so the tip's lever is the whole reach through the mimic slide.
      const std::size_t w = std::find(m.variable_names().begin(), m.variable_names().end(), "wrist") - m.variable_names().begin();
      start[s] = goal[s] = 0.1;
      start[w] = goal[w] = -M_PI / 2;
    }
    outside += std::abs(start[s]) > 0.1;
    std::vector<double> speed(m.links().size());
    for (std::size_t l = 0; l < speed.size(); ++l) speed[l] = checker.link_speed(static_cast<int>(l), start.data(), goal.data());
    // Along the segment, every vertex's displacement between nearby fractions within the bound.
    for (double f = 0.0; f < 1.0; f += 0.125) {
      std::vector<double> qa(3), qb(3);
      for (std::size_t j = 0; j < 3; ++j) {
        qa[j] = start[j] + f * (goal[j] - start[j]);
        qb[j] = start[j] + (f + 0.01) * (goal[j] - start[j]);
      }
      const auto a = link_vertices(m, qa), b = link_vertices(m, qb);
      for (std::size_t l = 0; l < a.size(); ++l) {
        for (std::size_t k = 0; k < a[l].size(); ++k) {
          ASSERT_LE((b[l][k] - a[l][k]).norm(), 0.01 * speed[l] * (1 + 1e-12) + 1e-15)
              << m.links()[l].name << " slide " << start[s] << " -> " << goal[s];
        }
      }
    }
  }
  EXPECT_GT(outside, 100);
  EXPECT_LT(outside, 300);
}

// A link's speed sums only the variables that move it (RobotCollisionModel::motion_terms): the
// same bits as the sum over every variable, whose other terms are zeros; pr2's links are moved by
// a few of its variables each.
TEST(MotionRates, LinkSpeedSumsOnlyTheVariablesThatMoveTheLink) {
  BVH_REQUIRE_ROBOTS();
  for (const char* robot : {"panda", "pr2"}) {
    SCOPED_TRACE(robot);
    const CollisionChecker checker = test::load_checker(robot);
    const RobotCollisionModel& m = checker.collision_model();
    const std::size_t n = checker.model().variable_count();
    std::size_t terms = 0;
    for (const auto& link : m.motion_terms()) terms += link.size();
    if (std::string(robot) == "pr2") {
      EXPECT_LT(4 * terms, m.motion_terms().size() * n);
    }
    for (int i = 0; i < 200; ++i) {
      const auto start = random_configuration(checker.model(), rng()), goal = random_configuration(checker.model(), rng());
      for (std::size_t l = 0; l < m.motion_terms().size(); ++l) {
        double speed = 0.0, turning = 0.0;
        for (std::size_t j = 0; j < n; ++j) {
          const double change = std::abs(goal[j] - start[j]);
          speed += m.motion_rates()[l][j] * change;
          turning += m.motion_turns()[l][j] * change;
        }
        double excess = 0.0;
        for (const SlideBound& slide : m.motion_slides()[l]) {
          const double farthest = std::max(std::abs(start[slide.variable]), std::abs(goal[slide.variable]));
          excess += slide.multiplier * std::max(0.0, farthest - slide.travel);
        }
        ASSERT_EQ(checker.link_speed(static_cast<int>(l), start.data(), goal.data()), speed + excess * turning);
      }
    }
  }
}

// A scene for motions: a table-top box and a thin plate (2 mm) standing in the arm's way.
Environment motion_scene(double plate_thickness) {
  Environment env(0.02);
  env.add_object("table", ObjectShape::box(Vec3(0.6, 1.2, 0.05)), Transform::Translation(Vec3(0.6, 0.0, 0.2)));
  env.add_object("plate", ObjectShape::box(Vec3(plate_thickness, 0.6, 0.6)), Transform::Translation(Vec3(0.45, 0.0, 0.7)));
  return env;
}

bool state_collides(const CollisionChecker& checker, const double* q, const Environment& env) {
  return checker.check_self(q).collision || checker.check_environment(q, env).collision;
}

TEST(Motion, SteppedEqualsOneCheckPerState) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const Environment env = motion_scene(0.02);
  int invalid = 0;
  for (int i = 0; i < 30; ++i) {
    const auto a = random_configuration(checker.model(), rng()), b = random_configuration(checker.model(), rng());
    MotionRequest request;
    request.resolution = 0.1;
    const MotionResult got = checker.check_motion(a.data(), b.data(), env, request);
    double longest = 0.0;
    for (std::size_t j = 0; j < a.size(); ++j) longest = std::max(longest, std::abs(b[j] - a[j]));
    const int steps = static_cast<int>(std::ceil(longest / 0.1));
    double last = 0.0;
    bool valid = true;
    for (int k = 0; k <= steps && valid; ++k) {
      std::vector<double> q(a.size());
      for (std::size_t j = 0; j < a.size(); ++j) q[j] = k == steps ? b[j] : a[j] + (b[j] - a[j]) * k / steps;
      valid = !state_collides(checker, q.data(), env);
      if (valid) last = static_cast<double>(k) / steps;
    }
    EXPECT_EQ(got.valid, valid) << i;
    if (!valid) {
      EXPECT_DOUBLE_EQ(got.last_valid_fraction, last) << i;
    }
    invalid += !valid;
  }
  EXPECT_GT(invalid, 3);
  EXPECT_LT(invalid, 30);
}

// A dense sweep (2,000 states) as the oracle: a certified "valid" must see no colliding state in
// it, and a certified "invalid" must stop no later than the sweep's first collision.
TEST(Motion, CertifiedNeverMissesWhatADenseSweepFinds) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const Environment env = motion_scene(0.002);
  int valid = 0, invalid = 0;
  for (int i = 0; i < 12; ++i) {
    const auto a = random_configuration(checker.model(), rng()), b = random_configuration(checker.model(), rng());
    if (state_collides(checker, a.data(), env)) continue;
    const MotionResult got = checker.check_motion(a.data(), b.data(), env);
    ASSERT_TRUE(got.certified) << got.message;
    // (Under the sanitizers, whose pass looks for memory errors, a quarter as dense: a coarser
    // sweep can only miss collisions, which makes the check weaker there, never wrong.)
    const int steps = test::sanitized() ? 500 : 2000;
    double first = 2.0;
    for (int k = 0; k <= steps && first > 1.0; ++k) {
      std::vector<double> q(a.size());
      for (std::size_t j = 0; j < a.size(); ++j) q[j] = k == steps ? b[j] : a[j] + (b[j] - a[j]) * k / double(steps);
      if (state_collides(checker, q.data(), env)) first = k / double(steps);
    }
    if (got.valid) {
      EXPECT_GT(first, 1.0) << i << ": certified valid, but the sweep collides at " << first;
    } else {
      EXPECT_LE(got.last_valid_fraction, first) << i;
    }
    valid += got.valid;
    invalid += !got.valid;
  }
  EXPECT_GT(valid + invalid, 6);
}

TEST(Motion, CertifiedFindsAThinPlateACoarseStepMisses) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  Environment env(0.02);
  // A 1 mm plate across the hand's path as joint 1 swings from -0.6 to 0.6 rad.
  std::vector<double> a(checker.model().variable_count(), 0.0);
  const auto& names = checker.model().variable_names();
  auto set = [&](std::vector<double>& q, const std::string& joint, double v) {
    q[std::find(names.begin(), names.end(), joint) - names.begin()] = v;
  };
  set(a, "panda_joint2", -0.785);  // panda's "ready" pose
  set(a, "panda_joint4", -2.356);
  set(a, "panda_joint6", 1.571);
  set(a, "panda_joint7", -0.785);  // the hand's long side along the arm: it sweeps its narrow side
  set(a, "panda_finger_joint1", 0.03);  // closed fingers touch each other
  std::vector<double> b = a;
  set(a, "panda_joint1", -0.6);
  set(b, "panda_joint1", 0.6);
  std::vector<Transform> poses;
  forward_kinematics(checker.model(), a.data(), poses);
  const Vec3 hand = poses[checker.model().link_index("panda_hand")].t;
  const double radius = std::hypot(hand.x(), hand.y());
  // The plate stands in the plane y = 0 (joint 1 at 0 puts the hand there), at the hand's reach.
  env.add_object("plate", ObjectShape::box(Vec3(0.02, 0.001, 0.02)), Transform::Translation(Vec3(radius, 0.0, hand.z())));
  ASSERT_FALSE(checker.check_self(a.data()).collision);
  ASSERT_FALSE(checker.check_environment(a.data(), env).collision) << "hand at " << hand.transpose();
  ASSERT_FALSE(state_collides(checker, b.data(), env));
  // The colliding stretch of joint 1 is [-w, w] (a dense sweep); n steps, n odd, put the states
  // nearest 0 at +-0.6 / n, outside it when n < 0.6 / w.
  double w = 0.0;
  for (int k = 0; k <= 1200; ++k) {
    std::vector<double> q = a;
    set(q, "panda_joint1", -0.6 + k * 0.001);
    if (state_collides(checker, q.data(), env)) w = std::max(w, std::abs(-0.6 + k * 0.001));
  }
  ASSERT_GT(w, 0.0) << "the plate is not in the way";
  std::cout << "plate in the way for joint 1 in [-" << w << ", " << w << "]\n";
  int n = static_cast<int>(std::ceil(0.6 / w)) - 1;
  if (n % 2 == 0) --n;
  ASSERT_GE(n, 3) << "the plate is in the way of too much of the motion to make a coarse step miss it";
  MotionRequest coarse;
  coarse.resolution = 1.2 / n;
  const MotionResult stepped = checker.check_motion(a.data(), b.data(), env, coarse);
  const MotionResult certified = checker.check_motion(a.data(), b.data(), env);
  EXPECT_TRUE(stepped.valid) << "the coarse step should miss the plate (else the test shows nothing)";
  EXPECT_FALSE(certified.valid);
  EXPECT_TRUE(certified.certified);
  EXPECT_LT(certified.last_valid_fraction, 0.5);
  EXPECT_GT(certified.last_valid_fraction, 0.2);
}

// The public certified check is the planner's engine (query/scene_checker.h) on a scene prepared
// for the snapshot and kept: it answers as a SceneChecker built for it, as conservative
// advancement (advancement_oracle.h, another algorithm), and a motion asked again on the same
// snapshot (or an unchanged copy) comes from the kept scene's memory. On main the public path was
// conservative advancement itself, 24-58 ms a segment where the planner's took 21-64 us. A
// changed world is a new snapshot: never answered from the old scene.
TEST(Motion, CertifiedIsThePlannersEngineOnAKeptScene) {
  const CollisionChecker checker = test::demo_arm_checker();
  Environment env(0.05);
  env.add_object("pillar", ObjectShape::box({0.12, 0.12, 0.8}), Transform::Translation({0.45, 0.35, 0.4}));
  std::mt19937_64 local(21);
  // Until enough motions are compared, colliding ones among them (a sanitized run asks fewer).
  const int wanted = test::sized(24);
  int compared = 0, colliding = 0;
  for (int i = 0; i < 400 && (compared < wanted || colliding < 2); ++i) {
    const std::vector<double> a = random_configuration(checker.model(), local), b = random_configuration(checker.model(), local);
    if (state_collides(checker, a.data(), env)) continue;
    const MotionResult got = checker.check_motion(a.data(), b.data(), env);
    // Asked again, on the snapshot and on an unchanged copy of it: from the kept scene's memory.
    EXPECT_EQ(checker.check_motion(a.data(), b.data(), env).states_checked, 0u) << "motion " << i;
    const Environment copy = env;
    EXPECT_EQ(checker.check_motion(a.data(), b.data(), copy).states_checked, 0u) << "motion " << i;
    // (A scene checker of its own: its memory takes the thread's slot for this motion.)
    const SceneChecker scene(checker, std::make_shared<const Environment>(env));
    const MotionResult engine = scene.check_motion(a.data(), b.data(), true);
    ASSERT_EQ(got.valid, engine.valid) << "motion " << i;
    ASSERT_EQ(got.last_valid_fraction, engine.last_valid_fraction) << "motion " << i;
    EXPECT_EQ(got.valid, test::advancement_motion(checker, a.data(), b.data(), env).valid) << "motion " << i;
    ++compared;
    colliding += !got.valid;
  }
  EXPECT_GE(compared, wanted);
  EXPECT_GE(colliding, 2);
  // A motion free among the pillar alone, then a box put across it: the new snapshot answers.
  std::vector<double> a(checker.model().variable_count(), 0.0), b = a;
  b[0] = 1.5;  // joint1 turns the upright arm
  ASSERT_TRUE(checker.check_motion(a.data(), b.data(), env).valid);
  Environment changed = env;
  std::vector<Transform> poses;
  forward_kinematics(checker.model(), a.data(), poses);
  changed.add_object("in_the_way", ObjectShape::box({0.05, 0.05, 0.05}), Transform::Translation(poses[checker.model().link_index("hand")].t));
  const MotionResult now = checker.check_motion(a.data(), b.data(), changed);
  EXPECT_FALSE(now.valid);
  EXPECT_GT(now.states_checked, 0u);
  // Another tolerance, another prepared scene: its own answer, not the kept one's.
  MotionRequest tolerant;
  tolerant.tolerance = 0.01;
  EXPECT_GT(checker.check_motion(a.data(), b.data(), env, tolerant).states_checked, 0u);
}

TEST(Motion, BadInput) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const Environment env(0.05);
  std::vector<double> a(checker.model().variable_count(), 0.0);
  a[1] = -0.785;  // "ready": free
  a[3] = -2.356;
  a[5] = 1.571;
  a[checker.model().variable_count() - 1] = 0.03;  // panda_finger_joint1: closed fingers touch
  ASSERT_EQ(checker.model().variable_names().back(), "panda_finger_joint1");
  std::vector<double> b = a;
  MotionRequest r;
  r.resolution = -1;
  EXPECT_THROW(checker.check_motion(a.data(), b.data(), env, r), std::invalid_argument);
  r.resolution = 0;
  r.tolerance = std::nan("");
  EXPECT_THROW(checker.check_motion(a.data(), b.data(), env, r), std::invalid_argument);
  b[0] = std::numeric_limits<double>::infinity();
  EXPECT_THROW(checker.check_motion(a.data(), b.data(), env), std::invalid_argument);
  b = a;
  // Start equals goal: one state, valid.
  const MotionResult same = checker.check_motion(a.data(), a.data(), env);
  EXPECT_TRUE(same.valid);
  EXPECT_EQ(same.last_valid_fraction, 1.0);
}

// Brute force: every link and object triangle (exact segment test, distance from the plane),
// every sphere, every occupied leaf (slabs).
double brute_force_ray(const CollisionChecker& checker, const std::vector<double>& state, const Environment& env,
                       const Vec3& o, const Vec3& u, double range, std::string* body) {
  double best = range;
  auto triangle = [&](const Vec3& a, const Vec3& b, const Vec3& c, const std::string& name) {
    if (!segment_intersects_triangle(o, o + best * u, a, b, c)) return;
    const Vec3 n = (b - a).cross(c - a);
    const double t = std::abs(n.dot(u)) > 1e-12 ? n.dot(a - o) / n.dot(u) : 0.0;
    if (t < best) {
      best = std::max(0.0, t);
      *body = name;
    }
  };
  std::vector<Transform> poses;
  forward_kinematics(checker.model(), state.data(), poses);
  for (std::size_t l = 0; l < poses.size(); ++l) {
    for (const CollisionElement& e : checker.model().links()[l].collision) {
      const Transform p = poses[l] * e.origin;
      if (!e.mesh) continue;
      for (const auto& f : e.mesh->triangles) {
        triangle(p * e.mesh->vertices[f[0]], p * e.mesh->vertices[f[1]], p * e.mesh->vertices[f[2]], checker.model().links()[l].name);
      }
    }
  }
  for (const CollisionObject& obj : env.objects()) {
    const double t = ray_ball_entry(o, u, best, obj.pose.t, obj.shape.kind == ObjectShape::Kind::kSphere ? obj.shape.radius : -1);
    if (obj.shape.kind == ObjectShape::Kind::kSphere && t < best) {
      best = t;
      *body = obj.id;
    }
    if (!obj.mesh) continue;
    for (std::int32_t i = 0; i < static_cast<std::int32_t>(obj.mesh->triangles().size()); ++i) {
      const Triangle& t3 = obj.mesh->triangles()[i];
      triangle(obj.pose * t3[0], obj.pose * t3[1], obj.pose * t3[2], obj.id);
    }
  }
  for (const Octree::Leaf& leaf : env.octree().leaves()) {
    if (!env.octree().occupied(leaf.log_odds)) continue;
    const Vec3 lo = env.octree().cube_min(leaf.key), hi = lo + Vec3::Constant(env.octree().cube_size(leaf.depth));
    double t0 = 0.0, t1 = best;
    for (int k = 0; k < 3 && t0 <= t1; ++k) {
      if (u[k] == 0.0) {
        if (o[k] < lo[k] || o[k] > hi[k]) t0 = 2 * best + 1;
        continue;
      }
      const double s1 = (lo[k] - o[k]) / u[k], s2 = (hi[k] - o[k]) / u[k];
      t0 = std::max(t0, std::min(s1, s2));
      t1 = std::min(t1, std::max(s1, s2));
    }
    if (t0 <= t1 && t0 < best) {
      best = t0;
      *body = "octree";
    }
  }
  return best;
}

TEST(RayCast, AgainstBruteForce) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  Environment env = motion_scene(0.02);
  env.add_object("ball", ObjectShape::sphere(0.1), Transform::Translation(Vec3(-0.4, 0.4, 0.5)));
  std::vector<ScanPoint> wall;
  for (float y = -1.0f; y <= 1.0f; y += 0.01f)
    for (float z = 0.0f; z <= 1.0f; z += 0.01f) wall.emplace_back(-0.8f, y, z);
  insert_points(env.octree(), wall);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits[4] = {0, 0, 0, 0};
  for (int i = 0; i < 400; ++i) {
    const auto q = random_configuration(checker.model(), rng());
    const Vec3 origin(1.5 * u(rng()), 1.5 * u(rng()), 0.5 + 0.8 * u(rng()));
    const Vec3 target(0.5 * u(rng()), 0.5 * u(rng()), 0.5 + 0.5 * u(rng()));
    const Vec3 dir = (target - origin) * (1.0 + u(rng()));
    const RayCastResult got = checker.cast_ray(q.data(), env, origin, dir, 5.0);
    std::string body;
    const double want = brute_force_ray(checker, q, env, origin, dir.normalized(), 5.0, &body);
    if (want >= 5.0) {
      EXPECT_FALSE(got.hit) << i;
      ++hits[3];
      continue;
    }
    ASSERT_TRUE(got.hit) << i << " expected " << body << " at " << want;
    EXPECT_NEAR(got.distance, want, 1e-9) << i;
    const std::string name = got.octree ? "octree" : got.link >= 0 ? checker.model().links()[got.link].name : got.object;
    if (std::abs(got.distance - want) < 1e-9 && name != body) continue;  // a tie between two bodies
    EXPECT_EQ(name, body) << i;
    ++hits[got.octree ? 2 : got.link >= 0 ? 0 : 1];
  }
  EXPECT_GT(hits[0], 20);  // links
  EXPECT_GT(hits[1], 20);  // objects
  EXPECT_GT(hits[2], 10);  // voxels
  EXPECT_GT(hits[3], 20);  // nothing
  const auto q = random_configuration(checker.model(), rng());
  EXPECT_THROW(checker.cast_ray(q.data(), env, Vec3::Zero(), Vec3::Zero(), 1.0), std::invalid_argument);
  EXPECT_THROW(checker.cast_ray(q.data(), env, Vec3(std::nan(""), 0, 0), Vec3::UnitX(), 1.0), std::invalid_argument);
  EXPECT_FALSE(checker.cast_ray(q.data(), env, Vec3(0, 0, 5), Vec3::UnitZ(), -1.0).hit);  // unlimited, up into nothing
}

// A moving base: the robot with its root at T against the objects equals the robot at the origin
// against the objects moved by T^-1.
TEST(RootPose, MovingTheBaseEqualsMovingTheWorldTheOtherWay) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker checker = test::load_checker("panda");
  const Environment env = motion_scene(0.02);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  int colliding = 0;
  for (int i = 0; i < 100; ++i) {
    const Transform base = test::random_rotation(rng(), Vec3(u(rng()), u(rng()), 0.5 * u(rng())));
    Environment moved(0.02);
    for (const CollisionObject& o : env.objects()) moved.add_object(o.id, o.shape, base.inverse() * o.pose);
    const auto q = random_configuration(checker.model(), rng());
    EnvironmentRequest at_base;
    at_base.root_pose = base;
    at_base.distance = true;
    EnvironmentRequest at_origin;
    at_origin.distance = true;
    const EnvironmentResult a = checker.check_environment(q.data(), env, at_base);
    const EnvironmentResult b = checker.check_environment(q.data(), moved, at_origin);
    ASSERT_EQ(a.collision, b.collision) << i;
    EXPECT_NEAR(a.min_distance, b.min_distance, 1e-9) << i;
    colliding += a.collision;
    const Vec3 origin = base * Vec3(1.5, 0.2, 0.6), target = base * Vec3(0.0, 0.0, 0.5);
    const RayCastResult ra = checker.cast_ray(q.data(), env, origin, target - origin, 5.0, base);
    const RayCastResult rb = checker.cast_ray(q.data(), moved, base.inverse() * origin, base.R.transpose() * (target - origin), 5.0);
    ASSERT_EQ(ra.hit, rb.hit) << i;
    if (ra.hit) {
      EXPECT_NEAR(ra.distance, rb.distance, 1e-9) << i;
    }
  }
  EXPECT_GT(colliding, 5);
  // The self filter too: points around a robot based at T, against the same points moved by T^-1
  // and the robot at the origin (a dyadic shift, so the moved floats are the same points).
  const Transform shift = Transform::Translation(Vec3(0.25, -0.5, 0.125));
  std::uniform_real_distribution<float> box(-0.8f, 0.8f);
  std::vector<ScanPoint> near_base, near_origin;
  for (int i = 0; i < 5000; ++i) {
    const ScanPoint p(box(rng()), box(rng()), 0.6f + box(rng()));
    near_origin.push_back(p);
    near_base.push_back((p + shift.t.cast<float>()).eval());
  }
  const ScanPoint sensor(1.0f, 0.5f, 1.0f);
  const auto state = random_configuration(checker.model(), rng());
  const FilteredScan at_t = checker.filter_scan(state.data(), near_base, (sensor + shift.t.cast<float>()).eval(), 0.02, shift);
  const FilteredScan at_0 = checker.filter_scan(state.data(), near_origin, sensor, 0.02);
  EXPECT_GT(at_0.on_robot + at_0.shadowed, 50u);
  EXPECT_NEAR(double(at_t.on_robot), double(at_0.on_robot), 2.0);  // a point on a boundary may round either way
  EXPECT_NEAR(double(at_t.shadowed), double(at_0.shadowed), 2.0);
  EnvironmentRequest bad;
  bad.root_pose.R(0, 0) = 2.0;
  const auto q = random_configuration(checker.model(), rng());
  EXPECT_THROW(checker.check_environment(q.data(), env, bad), std::invalid_argument);
}

}  // namespace
}  // namespace bvh_collision
