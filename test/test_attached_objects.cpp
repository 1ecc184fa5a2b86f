// Objects the robot carries (AttachedBody, CollisionChecker::carrying) against an independent
// oracle: the same robot loaded from a URDF with one more link that holds the same shapes on a
// fixed joint, its touch links allowed in the matrix. Every query must answer for the carried
// object as for that link: self checks (collision, pairs, distance), environment checks,
// SceneChecker's states and certified motions, the self filter and rays.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <tuple>

#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

// A URDF <origin>'s rotation: R = Rz(yaw) Ry(pitch) Rx(roll).
Transform urdf_origin(const Vec3& xyz, const Vec3& rpy) {
  Transform t;
  t.R = (Eigen::AngleAxisd(rpy.z(), Vec3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vec3::UnitY()) *
         Eigen::AngleAxisd(rpy.x(), Vec3::UnitX())).toRotationMatrix();
  t.t = xyz;
  return t;
}

// The carried object: a box across the fingers, a sphere and a cylinder beyond them, in
// panda_hand's frame, as three shapes of one object and as the oracle's link elements.
struct HeldShape {
  ObjectShape shape;
  Vec3 xyz, rpy;
  std::string urdf;
};

std::vector<HeldShape> held_shapes() {
  return {{ObjectShape::box(Vec3(0.05, 0.04, 0.08)), Vec3(0.0, 0.0, 0.11), Vec3(0.1, 0.0, 0.3), "<box size=\"0.05 0.04 0.08\"/>"},
          {ObjectShape::sphere(0.03), Vec3(0.02, 0.0, 0.17), Vec3::Zero(), "<sphere radius=\"0.03\"/>"},
          {ObjectShape::cylinder(0.012, 0.14), Vec3(0.0, 0.03, 0.15), Vec3(0.0, 1.2, 0.0), "<cylinder radius=\"0.012\" length=\"0.14\"/>"}};
}

std::string panda_dir() { return test::robots_dir() + "/panda"; }

std::string read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Panda as MoveIt sets it up, with `extra_urdf` inserted before </robot> and `touch` allowed
// with link "held" (when it exists).
CollisionChecker panda_with(const std::string& extra_urdf, const std::vector<std::string>& touch,
                            const CheckerOptions& options) {
  std::string urdf = read(panda_dir() + "/robot.urdf");
  urdf.insert(urdf.rfind("</robot>"), extra_urdf);
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(urdf), PackageResolver({panda_dir()}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  apply_srdf(parse_srdf(read(panda_dir() + "/robot.srdf"), &model), model, acm);
  const int held = model.link_index("held");
  for (const std::string& name : touch) acm.allow(held, model.link_index(name), AcmReason::kSrdf);
  return CollisionChecker(std::move(model), std::move(acm), options);
}

std::string held_link_urdf() {
  std::ostringstream out;
  out << "<link name=\"held\">";
  for (const HeldShape& s : held_shapes()) {
    out << "<collision><origin xyz=\"" << s.xyz.x() << " " << s.xyz.y() << " " << s.xyz.z() << "\" rpy=\"" << s.rpy.x()
        << " " << s.rpy.y() << " " << s.rpy.z() << "\"/><geometry>" << s.urdf << "</geometry></collision>";
  }
  out << "</link><joint name=\"held_joint\" type=\"fixed\"><parent link=\"panda_hand\"/><child link=\"held\"/></joint>";
  return out.str();
}

AttachedBody held_body(const std::vector<std::string>& touch) {
  AttachedBody body{"held", "panda_hand", touch, {}};
  const std::vector<HeldShape> shapes = held_shapes();
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    body.shapes.push_back(make_collision_object("held#" + std::to_string(k), shapes[k].shape, urdf_origin(shapes[k].xyz, shapes[k].rpy)));
  }
  return body;
}

const std::vector<std::string> kFingers = {"panda_leftfinger", "panda_rightfinger"};

struct Pair {
  CollisionChecker ours, oracle;
};

const Pair& checkers() {
  static const Pair pair = [] {
    // Two proxy levels (5 mm alone takes most of panda's build); the oracle reads the robot's
    // link proxies from the tests' cache (test::proxy_cache_dir) as this one does.
    CheckerOptions options;
    options.proxy_levels = {0.01, 0.02};
    options.proxy_cache = test::proxy_cache_dir();
    const CollisionChecker base = test::panda_as_moveit(options);
    Environment env(0.05);
    env.attach(held_body(kFingers));
    const auto t0 = std::chrono::steady_clock::now();
    CollisionChecker ours = base.carrying(env);
    std::printf("carrying: %.1f ms\n", std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    Pair out{std::move(ours), panda_with(held_link_urdf(), kFingers, options)};
    return out;
  }();
  return pair;
}

std::vector<std::vector<double>> random_states(const CollisionChecker& checker, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> out;
  for (int i = 0; i < count; ++i) out.push_back(random_configuration(checker.model(), rng));
  return out;
}

// The pairs a result names, by link names (the two models number the carried link differently).
std::set<std::pair<std::string, std::string>> named(const CollisionChecker& c, const std::vector<std::pair<int, int>>& pairs) {
  std::set<std::pair<std::string, std::string>> out;
  for (const auto& [a, b] : pairs) {
    const std::string na = c.model().links()[a].name, nb = c.model().links()[b].name;
    out.emplace(std::min(na, nb), std::max(na, nb));
  }
  return out;
}

TEST(AttachedObjects, CarriedBodyIsOneMoreLink) {
  const CollisionChecker& ours = checkers().ours;
  const CollisionChecker base = test::panda_as_moveit();
  ASSERT_EQ(ours.model().links().size(), base.model().links().size() + 1);
  EXPECT_EQ(ours.collision_model().robot_link_count(), base.model().links().size());
  EXPECT_EQ(ours.model().variable_count(), base.model().variable_count());
  const int held = ours.model().link_index("held");
  ASSERT_GE(held, 0);
  EXPECT_EQ(ours.collision_model().shapes()[held].size(), 3u);
  // The robot's own pairs first, unchanged; then the carried body's, none with its link or touch links.
  for (std::size_t p = 0; p < base.checked_pairs().size(); ++p) {
    EXPECT_EQ(ours.checked_pairs()[p], base.checked_pairs()[p]);
  }
  EXPECT_EQ(named(ours, ours.checked_pairs()), named(checkers().oracle, checkers().oracle.checked_pairs()));
  // A proxy at every level, as a link's.
  for (const ProxyLevel& level : ours.accelerators().proxy_levels()) {
    ASSERT_EQ(level.links.size(), ours.model().links().size());
    EXPECT_GT(level.links[held].leaf_count(), 0u) << level.level;
  }
}

TEST(AttachedObjects, SelfChecksMatchTheLinkOracle) {
  const Pair& c = checkers();
  int colliding = 0, with_held = 0;
  for (const auto& q : random_states(c.ours, test::sized(400), 7)) {
    SelfCollisionRequest request;
    request.all_pairs = true;
    request.distance = true;
    const SelfCollisionResult a = c.ours.check_self(q.data(), request), b = c.oracle.check_self(q.data(), request);
    ASSERT_EQ(a.collision, b.collision);
    EXPECT_EQ(named(c.ours, a.colliding_pairs), named(c.oracle, b.colliding_pairs));
    if (!a.collision) {
      EXPECT_NEAR(a.min_distance, b.min_distance, 1e-9);
    }
    colliding += a.collision;
    for (const auto& [x, y] : named(c.ours, a.colliding_pairs)) with_held += x == "held" || y == "held";
  }
  EXPECT_GT(with_held, 5);  // the carried object hits the arm in some states
  EXPECT_LT(colliding, test::sized(400));
}

TEST(AttachedObjects, TouchLinksAndTheOwnLinkAreAllowed) {
  const CollisionChecker base = test::panda_as_moveit();
  // The box reaches between the fingers: without touch links the fingers collide with it.
  const CollisionChecker bare = base.carrying({held_body({})}, {});
  std::vector<double> q(base.model().variable_count(), 0.0);
  q[3] = -1.5, q[5] = 1.5;
  const SelfCollisionResult hit = bare.check_self(q.data(), SelfCollisionRequest{0.0, true});
  ASSERT_TRUE(hit.collision);
  for (const auto& [a, b] : named(bare, hit.colliding_pairs)) {
    EXPECT_TRUE(a == "held" || b == "held");
  }
  EXPECT_FALSE(base.carrying({held_body(kFingers)}, {}).check_self(q.data()).collision);
  // The environment's allowed collisions name the object too (one entry per finger).
  NamedAllowedCollisions allowed;
  for (const std::string& f : kFingers) allowed.set_entry("held", f, true);
  EXPECT_FALSE(base.carrying({held_body({})}, allowed).check_self(q.data()).collision);
}

TEST(AttachedObjects, RefusesWhatCannotBeCarried) {
  const CollisionChecker base = test::panda_as_moveit();
  AttachedBody body = held_body(kFingers);
  body.link = "no_such_link";
  EXPECT_THROW(base.carrying({body}, {}), std::invalid_argument);
  body = held_body({"no_such_finger"});
  EXPECT_THROW(base.carrying({body}, {}), std::invalid_argument);
  body = held_body(kFingers);
  body.id = "panda_link3";  // a link's name
  EXPECT_THROW(base.carrying({body}, {}), std::invalid_argument);
  EXPECT_THROW(base.carrying({held_body(kFingers), held_body(kFingers)}, {}), std::invalid_argument);
  Environment env(0.05);
  EXPECT_THROW(env.attach(AttachedBody{"a#1", "panda_hand", {}, held_body({}).shapes}), std::invalid_argument);
  EXPECT_THROW(env.attach(AttachedBody{"a", "panda_hand", {}, {}}), std::invalid_argument);
  EXPECT_TRUE(env.attached().empty());
  env.attach(held_body({}));
  env.attach(held_body(kFingers));  // replaces
  ASSERT_EQ(env.attached().size(), 1u);
  EXPECT_EQ(env.find_attached("held")->touch_links, kFingers);
  const Environment before = env;
  EXPECT_FALSE(env.detach("other"));
  EXPECT_TRUE(env.detach("held"));
  EXPECT_TRUE(env.attached().empty());
  EXPECT_EQ(before.attached().size(), 1u);  // a snapshot keeps its list
}

TEST(AttachedObjects, EnvironmentAndSceneChecksMatchTheLinkOracle) {
  const Pair& c = checkers();
  int hits_by_held = 0;
  for (int k = 0; k < 4; ++k) {
    const auto env = std::make_shared<const Environment>(test::generate_scene(2026, k).environment());
    SceneCheckOptions tolerant;
    tolerant.tolerance = 0.01;
    const SceneChecker ours(c.ours, env), oracle(c.oracle, env), ours_tolerant(c.ours, env, tolerant);
    for (const auto& q : random_states(c.ours, test::sized(150), 100 + k)) {
      EnvironmentRequest request;
      request.all_links = true;
      request.distance = true;
      const EnvironmentResult a = c.ours.check_environment(q.data(), *env, request);
      const EnvironmentResult b = c.oracle.check_environment(q.data(), *env, request);
      ASSERT_EQ(a.collision, b.collision);
      ASSERT_EQ(a.contacts.size(), b.contacts.size());
      for (std::size_t i = 0; i < a.contacts.size(); ++i) {
        hits_by_held += c.ours.model().links()[a.contacts[i].link].name == "held";
      }
      if (!a.collision) {
        EXPECT_NEAR(a.min_distance, b.min_distance, 1e-9);
      }
      const bool expected = oracle.collides(q.data());
      EXPECT_EQ(ours.collides(q.data()), expected);
      EXPECT_EQ(ours_tolerant.collides(q.data()), expected);  // states stay exact at a tolerance
    }
  }
  EXPECT_GT(hits_by_held, 3);
}

// Certified motions: free by ours means free by the oracle's exact check at every sampled state
// (and the two certified checks agree at tolerance 0), at tolerance 0 and 1 cm.
TEST(AttachedObjects, CertifiedMotionsCarryTheObject) {
  const Pair& c = checkers();
  const auto env = std::make_shared<const Environment>(test::generate_scene(2026, 1).environment());
  const SceneChecker ours(c.ours, env), oracle(c.oracle, env);
  SceneCheckOptions tolerant;
  tolerant.tolerance = 0.01;
  const SceneChecker ours_tolerant(c.ours, env, tolerant);
  std::vector<std::vector<double>> free;
  for (const auto& q : random_states(c.ours, 400, 31)) {
    if (!oracle.collides(q.data())) free.push_back(q);
  }
  ASSERT_GT(free.size(), 20u);
  int valid = 0, agree = 0, cases = 0;
  for (std::size_t i = 0; i + 1 < free.size() && cases < test::sized(60); ++i, ++cases) {
    std::vector<double> goal = free[i + 1];
    for (std::size_t j = 0; j < goal.size(); ++j) goal[j] = free[i][j] + 0.3 * (goal[j] - free[i][j]);  // planner-like edges
    const MotionResult a = ours.check_motion(free[i].data(), goal.data());
    const MotionResult t = ours_tolerant.check_motion(free[i].data(), goal.data());
    agree += a.valid == oracle.check_motion(free[i].data(), goal.data()).valid;
    for (const MotionResult* r : {&a, &t}) {
      if (!r->valid) continue;
      std::vector<double> q(goal.size());
      for (int s = 0; s <= 200; ++s) {
        for (std::size_t j = 0; j < q.size(); ++j) q[j] = free[i][j] + (goal[j] - free[i][j]) * s / 200.0;
        ASSERT_FALSE(oracle.collides(q.data())) << "a motion answered free collides at " << s / 200.0;
      }
    }
    valid += a.valid;
  }
  EXPECT_EQ(agree, cases);
  EXPECT_GT(valid, 0);
  EXPECT_LT(valid, cases);
}

TEST(AttachedObjects, SelfFilterAndRaysSeeTheCarriedObject) {
  const Pair& c = checkers();
  const CollisionChecker base = test::panda_as_moveit();
  std::vector<double> q(base.model().variable_count(), 0.0);
  q[3] = -1.5, q[5] = 1.5;
  std::vector<Transform> poses;
  forward_kinematics(c.ours.model(), q.data(), poses);
  const Transform hand = poses[c.ours.model().link_index("panda_hand")];
  // Points on the sphere's surface, seen from a sensor beside it.
  const HeldShape sphere = held_shapes()[1];
  const Vec3 centre = hand * sphere.xyz;
  const Vec3 sensor = centre + Vec3(1.0, 0.0, 0.0);
  std::vector<ScanPoint> points;
  for (int i = 0; i < 20; ++i) {
    const double a = -0.8 + 0.08 * i;  // on the half facing the sensor
    points.push_back((centre + 0.03 * Vec3(std::cos(a), std::sin(a), 0.0)).cast<float>());
  }
  const FilteredScan carried = c.ours.filter_scan(q.data(), points, sensor.cast<float>(), 0.01);
  const FilteredScan bare = base.filter_scan(q.data(), points, sensor.cast<float>(), 0.01);
  EXPECT_EQ(carried.obstacles.size(), 0u);
  EXPECT_EQ(bare.obstacles.size(), points.size());
  const Environment empty(0.05);
  for (int i = 0; i < 50; ++i) {  // rays fanned across the object: as the oracle's link answers
    const Vec3 towards = centre + Vec3(0.0, 0.003 * (i % 10) - 0.015, 0.004 * (i / 10) - 0.01);
    const RayCastResult a = c.ours.cast_ray(q.data(), empty, sensor, (towards - sensor).normalized(), 0.0);
    const RayCastResult b = c.oracle.cast_ray(q.data(), empty, sensor, (towards - sensor).normalized(), 0.0);
    ASSERT_EQ(a.hit, b.hit);
    if (!a.hit) continue;
    EXPECT_EQ(c.ours.model().links()[a.link].name, c.oracle.model().links()[b.link].name);
    EXPECT_NEAR(a.distance, b.distance, 1e-9);
  }
  const RayCastResult ray = c.ours.cast_ray(q.data(), empty, sensor, (centre - sensor).normalized(), 0.0);
  ASSERT_TRUE(ray.hit);
  EXPECT_EQ(c.ours.model().links()[ray.link].name, "held");
}

// MoveIt's (object, object) entries: the carried object may rest on a world object, or touch
// another carried one, when an entry names the two.
TEST(AttachedObjects, EntriesBetweenTwoObjectsHoldForACarriedOne) {
  const CollisionChecker base = test::panda_as_moveit();
  std::vector<double> q(base.model().variable_count(), 0.0);
  q[3] = -1.5, q[5] = 1.5;
  std::vector<Transform> poses;
  forward_kinematics(base.model(), q.data(), poses);
  const Vec3 ball = poses[base.model().link_index("panda_hand")] * held_shapes()[1].xyz;
  Environment env(0.05);
  env.add_object("ball", ObjectShape::sphere(0.01), Transform::Translation(ball));  // inside the held sphere
  env.attach(held_body(kFingers));
  AttachedBody second{"second", "panda_link7", {}, {make_collision_object("second", ObjectShape::sphere(0.05), Transform::Translation(Vec3(0.0, 0.0, 0.347)))}};
  env.attach(second);  // 0.24 m down the hand: 1 cm into the held sphere
  const auto answers = [&] {
    const CollisionChecker carried = base.carrying(env);
    const SceneChecker scene(base, std::make_shared<const Environment>(env));
    EnvironmentRequest request;
    request.all_links = true;
    SelfCollisionRequest self;
    self.all_pairs = true;
    return std::make_tuple(named(carried, carried.check_self(q.data(), self).colliding_pairs),
                           carried.check_environment(q.data(), env, request).contacts.size(), scene.collides(q.data()));
  };
  const auto [pairs, contacts, collides] = answers();
  EXPECT_EQ(pairs, (std::set<std::pair<std::string, std::string>>{{"held", "second"}}));
  EXPECT_EQ(contacts, 1u);
  EXPECT_TRUE(collides);
  NamedAllowedCollisions allowed;
  allowed.set_entry("held", "ball", true);
  allowed.set_entry("second", "held", true);
  env.set_allowed_collisions(allowed);
  const auto [pairs_after, contacts_after, collides_after] = answers();
  EXPECT_TRUE(pairs_after.empty());
  EXPECT_EQ(contacts_after, 0u);
  EXPECT_FALSE(collides_after);
}

// A checker that does not carry an environment's attached objects would miss their collisions:
// the queries that take the environment refuse it; SceneChecker carries them itself.
TEST(AttachedObjects, AnEnvironmentsObjectsAreCarriedOrTheQueryIsRefused) {
  const Pair& c = checkers();
  CheckerOptions options;
  options.proxy_levels = {};
  const CollisionChecker base = test::panda_as_moveit(options);
  Environment env = test::generate_scene(2026, 2).environment();
  env.attach(held_body(kFingers));
  std::vector<double> q(base.model().variable_count(), 0.0);
  EXPECT_FALSE(base.carries(env));
  EXPECT_TRUE(c.ours.carries(env));
  EXPECT_THROW(base.check_environment(q.data(), env), std::invalid_argument);
  EXPECT_THROW(base.check_motion(q.data(), q.data(), env), std::invalid_argument);
  EXPECT_THROW(base.cast_ray(q.data(), env, Vec3::Zero(), Vec3::UnitX(), 1.0), std::invalid_argument);
  BatchRequest batch;
  EXPECT_THROW(base.check_batch(q.data(), 1, &env, batch), std::invalid_argument);
  EXPECT_NO_THROW(c.ours.check_environment(q.data(), env));
  const auto shared = std::make_shared<const Environment>(env);
  const SceneChecker from_base(base, shared), from_carried(c.ours, shared);
  EXPECT_TRUE(from_base.checker().carries(env));
  int differ = 0;
  for (const auto& state : random_states(base, test::sized(200), 77)) differ += from_base.collides(state.data()) != from_carried.collides(state.data());
  EXPECT_EQ(differ, 0);
}

}  // namespace
}  // namespace bvh_collision
