// Allowed collisions with objects (world/named_allowed_collisions.h), MoveIt's semantics,
// against a brute-force oracle: a link allowed to touch some objects is checked, alone, against
// an environment without them. Every query that meets objects is held to it: check_environment
// (boolean, contacts, distance), SceneChecker's states and certified motions.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "bvh_collision/query/allowed_contacts.h"
#include "bvh_collision/query/scene_checker.h"
#include "checker_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"
#include "advancement_oracle.h"

namespace bvh_collision {
namespace {

TEST(NamedAllowedCollisions, AnswersAsMoveItDoes) {
  NamedAllowedCollisions acm;
  EXPECT_TRUE(acm.empty());
  EXPECT_FALSE(acm.allowed("hand", "box"));  // no entry, no default: checked
  acm.set_default("box", true);
  EXPECT_TRUE(acm.allowed("hand", "box"));  // the object's default
  EXPECT_TRUE(acm.allowed("box", "finger"));
  acm.set_default("hand", false);
  EXPECT_FALSE(acm.allowed("hand", "box"));  // both defaults: allowed only if both allow
  acm.set_default("hand", true);
  EXPECT_TRUE(acm.allowed("hand", "box"));
  acm.set_entry("box", "hand", false);  // an entry wins over the defaults, in either order of names
  EXPECT_FALSE(acm.allowed("hand", "box"));
  EXPECT_EQ(acm.entry("hand", "box"), std::optional<bool>(false));
  acm.remove_entry("hand", "box");
  EXPECT_TRUE(acm.allowed("hand", "box"));
  acm.remove_default("box");
  acm.remove_default("hand");
  EXPECT_TRUE(acm.empty());
}

const CollisionChecker& panda() { return test::panda_with_proxies(); }

// Per link, the objects it may not touch; the oracle's environment for that link.
Environment without_allowed(const Environment& env, const std::string& link) {
  Environment out(0.05);
  for (std::size_t o = 0; o < env.objects().size(); ++o) {
    if (!env.allowed_collisions().allowed(link, object_name(env.objects()[o].id))) out.add_object(env.objects()[o]);
  }
  return out;
}

struct Oracle {
  bool collision = false;
  double distance = std::numeric_limits<double>::infinity();
};

// (distance = false: whether it collides only, for the dense sweeps; the distance is most of the cost.)
Oracle oracle(const CollisionChecker& checker, const double* q, const Environment& env, bool distance = true) {
  Oracle out;
  const auto& links = checker.model().links();
  for (std::size_t l = 0; l < links.size(); ++l) {
    if (links[l].collision.empty()) continue;
    std::vector<char> only(links.size(), 0);
    only[l] = 1;
    EnvironmentRequest request;
    request.distance = distance;
    request.only_links = &only;
    const EnvironmentResult r = checker.check_environment(q, without_allowed(env, links[l].name), request);
    out.collision = out.collision || r.collision;
    if (r.min_distance < out.distance) out.distance = r.min_distance;
  }
  return out;
}

// A generated scene with allowances of every kind: one object allowed with every link by its
// default entry, one with the hand and fingers by entries, one whose default allows but whose
// entry with the hand does not.
Environment scene_with_allowances(int index) {
  Environment env = test::generate_scene(2026, index).environment();
  NamedAllowedCollisions acm;
  std::vector<std::string> names;  // whole objects (a shape id#k belongs to id)
  for (const CollisionObject& o : env.objects()) {
    const std::string name = object_name(o.id);
    if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(name);
  }
  EXPECT_GE(names.size(), 3u);
  acm.set_default(names[0], true);
  for (const char* link : {"panda_hand", "panda_leftfinger", "panda_rightfinger", "panda_link7"}) acm.set_entry(link, names[1], true);
  acm.set_default(names[2], true);
  acm.set_entry("panda_hand", names[2], false);
  env.set_allowed_collisions(acm);
  return env;
}

TEST(AllowedObjects, EnvironmentChecksSkipAllowedPairs) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(5);
  int colliding = 0, changed = 0, states = 0;
  for (int scene = 0; scene < 4; ++scene) {
    const Environment env = scene_with_allowances(scene);
    Environment plain = env;
    plain.set_allowed_collisions({});
    for (int i = 0; i < test::sized(150); ++i, ++states) {
      const std::vector<double> q = random_configuration(checker.model(), rng);
      const Oracle truth = oracle(checker, q.data(), env);
      EnvironmentRequest request;
      request.distance = true;
      const EnvironmentResult r = checker.check_environment(q.data(), env, request);
      ASSERT_EQ(r.collision, truth.collision) << "scene " << scene << " state " << i;
      for (const EnvironmentContact& c : r.contacts) {
        ASSERT_FALSE(env.allowed_collisions().allowed(checker.model().links()[c.link].name, object_name(c.object))) << c.object;
      }
      if (!truth.collision) {
        ASSERT_NEAR(r.min_distance, truth.distance, 1e-9) << "scene " << scene << " state " << i;
      }
      colliding += truth.collision;
      const bool without = checker.check_environment(q.data(), plain, EnvironmentRequest{}).collision;
      changed += truth.collision != without;
      // What the checks skipped: allowed pairs only, some whenever the allowances freed the
      // state, none when nothing touches at all.
      const auto skipped = allowed_object_contacts(checker, q.data(), env);
      for (const auto& [link, object] : skipped) {
        ASSERT_TRUE(env.allowed_collisions().allowed(checker.model().links()[link].name, object));
      }
      if (without && !truth.collision) {
        ASSERT_FALSE(skipped.empty()) << "scene " << scene << " state " << i;
      }
      if (!without) {
        ASSERT_TRUE(skipped.empty()) << "scene " << scene << " state " << i;
      }
    }
  }
  // The library's certified motion (the interval engine behind CollisionChecker::check_motion), held
  // against conservative advancement (advancement_oracle.h) and a dense sweep of the oracle.
  const Environment env = scene_with_allowances(1);
  int motions_free = 0;
  for (int i = 0; i < test::sized(12); ++i) {
    const std::vector<double> a = random_configuration(checker.model(), rng);
    std::vector<double> b = a;
    for (double& v : b) v += std::uniform_real_distribution<double>(-0.2, 0.2)(rng);
    MotionRequest request;
    request.self = false;
    const bool free = checker.check_motion(a.data(), b.data(), env, request).valid;
    EXPECT_EQ(free, test::advancement_motion(checker, a.data(), b.data(), env, request).valid) << "motion " << i;
    if (!free) continue;
    ++motions_free;
    std::vector<double> q(a.size());
    for (int k = 0; k <= 100; ++k) {
      for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * k / 100.0;
      ASSERT_FALSE(oracle(checker, q.data(), env, false).collision) << "motion " << i << " at " << k;
    }
  }
  EXPECT_GT(motions_free, 0);
  std::cout << states << " states, " << colliding << " colliding, " << changed << " of them free only by the allowances; "
            << motions_free << " certified motions free\n";
  EXPECT_GT(changed, 0);  // the allowances decide some states
  EXPECT_GT(colliding, 0);
}

TEST(AllowedObjects, SceneCheckerStatesAndMotionsSkipAllowedPairs) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(6);
  int motions_free = 0;
  for (int scene = 0; scene < 3; ++scene) {
    const auto env = std::make_shared<const Environment>(scene_with_allowances(scene));
    for (const double tolerance : {0.0, 0.01}) {
      SceneCheckOptions options;
      options.tolerance = tolerance;
      options.self = false;
      const SceneChecker scene_checker(checker, env, options);
      for (int i = 0; i < test::sized(100); ++i) {
        const std::vector<double> q = random_configuration(checker.model(), rng);
        ASSERT_EQ(scene_checker.collides(q.data()), oracle(checker, q.data(), *env, false).collision) << "scene " << scene << " state " << i;
      }
      // Motions answered free are free by the oracle at every state of a dense sweep.
      for (int i = 0; i < test::sized(20); ++i) {
        const std::vector<double> a = random_configuration(checker.model(), rng);
        std::vector<double> b = a;
        for (double& v : b) v += std::uniform_real_distribution<double>(-0.3, 0.3)(rng);
        if (!scene_checker.check_motion(a.data(), b.data()).valid) continue;
        ++motions_free;
        std::vector<double> q(a.size());
        const int steps = test::sanitized() ? 50 : 200;  // the oracle's sweep (a quarter under the sanitizers)
        for (int k = 0; k <= steps; ++k) {
          for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + (b[j] - a[j]) * k / steps;
          ASSERT_FALSE(oracle(checker, q.data(), *env, false).collision) << "scene " << scene << " motion " << i << " at " << k;
        }
      }
    }
  }
  EXPECT_GT(motions_free, 5);
}

}  // namespace
}  // namespace bvh_collision
