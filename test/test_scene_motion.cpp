// SceneChecker's certified motions (query/scene_checker.h) against the checker's own general
// queries as the oracle: the interval growth holds every vertex of every link over sampled motion
// (a self pair's in the frame of its common ancestor); a motion answered free is free at every
// state of a dense sweep, and one answered colliding collides (at the tolerance) where it says; a
// stretch freed by one exact distance frees no other link or object. (A motion's tolerance:
// test_scene_tolerance.cpp.) One binary with test_scene_checker.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <limits>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/world/object_grid.h"
#include "bvh_collision/query/scene_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"
#include "mesh_fixtures.h"
#include "planning_scenes.h"
#include "robot_data.h"
#include "scene_checker_fixtures.h"
#include "advancement_oracle.h"

namespace bvh_collision {
namespace {

using scene_test::exact_clearance;
using scene_test::exact_collides;
using scene_test::panda;

// Panda as above with every link padded by `padding`, no proxy levels (exact booleans only).
const CollisionChecker& padded(double padding) {
  static std::map<double, CollisionChecker> checkers;
  auto it = checkers.find(padding);
  if (it == checkers.end()) {
    CheckerOptions options;
    options.padding = padding;  // (a self pair then by twice that: both links)
    it = checkers.emplace(padding, test::panda_as_moveit(options)).first;
  }
  return it->second;
}

// Link poses at fraction s of the straight segment from a to b.
std::vector<Transform> poses_along(const RobotModel& model, const std::vector<double>& a, const std::vector<double>& b, double s) {
  std::vector<double> q(a.size());
  for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + s * (b[j] - a[j]);
  std::vector<Transform> poses;
  forward_kinematics(model, q.data(), poses);
  return poses;
}

// Every vertex of every link at any instant of an interval lies within the link's growth of
// where it is at the interval's midpoint. A rigid displacement is affine in the point, so its
// length is convex and largest at a vertex of the link's hull: vertices prove it for every point.
TEST(SceneChecker, IntervalGrowthHoldsEveryVertex) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const auto env = std::make_shared<const Environment>(0.05);
  const SceneChecker scene(checker, env);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double tightest = 0.0;
  for (int i = 0; i < test::sized(60); ++i) {
    const std::vector<double> a = random_configuration(model, rng), b = random_configuration(model, rng);
    const double lo = unit(rng), hi = lo + (1.0 - lo) * unit(rng), mid = 0.5 * (lo + hi);
    auto at = [&](double s) { return poses_along(model, a, b, s); };
    const std::vector<Transform> centre = at(mid);
    for (int k = 0; k <= 10; ++k) {
      const std::vector<Transform> poses = at(lo + (hi - lo) * k / 10.0);
      for (std::size_t l = 0; l < poses.size(); ++l) {
        const double growth = scene.link_growth(static_cast<int>(l), a.data(), b.data(), lo, hi);
        // The motion's chain-length rate over the interval, which sieves an interval's links
        // before their growth is taken (and caps it), holds every vertex too.
        const double cap = grown_growth(checker.link_speed(static_cast<int>(l), a.data(), b.data()) * 0.5 * (hi - lo));
        for (const CollisionElement& e : model.links()[l].collision) {
          for (const Vec3& v : e.mesh->vertices) {
            const double moved = (poses[l] * (e.origin * v) - centre[l] * (e.origin * v)).norm();
            ASSERT_LE(moved, growth) << "link " << model.links()[l].name << " case " << i;
            ASSERT_LE(moved, cap) << "link " << model.links()[l].name << " case " << i;
            if (growth > 0) tightest = std::max(tightest, moved / growth);
          }
        }
      }
    }
  }
  std::cout << "largest vertex displacement / growth: " << tightest << "\n";
  EXPECT_GT(tightest, 0.05);  // the bound is not vacuous
}

// The bound follows the arm's pose: over a planner's short edges the growth stays close to the
// farthest a vertex really moves (sampled: a lower bound on it), where the chain's full length
// (each joint's lever as if the arm were stretched out) overstates it several times.
TEST(SceneChecker, IntervalGrowthFollowsThePose) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const SceneChecker scene(checker, std::make_shared<const Environment>(0.05));
  SceneCheckOptions moved_root;
  moved_root.root_pose = Transform{Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix(), Vec3(0.4, -1.2, 0.3)};
  const SceneChecker placed(checker, std::make_shared<const Environment>(0.05), moved_root);
  std::mt19937_64 rng(29);
  std::uniform_real_distribution<double> unit(0.0, 1.0), step(-0.3, 0.3);
  std::vector<double> ours, chain;  // sampled displacement / growth, per case and link
  for (int i = 0; i < 80; ++i) {  // (not reduced under the sanitizers: a median needs the cases)
    const std::vector<double> a = random_configuration(model, rng);
    std::vector<double> b = a;
    for (double& v : b) v += step(rng);
    const double lo = unit(rng), hi = lo + (1.0 - lo) * unit(rng), mid = 0.5 * (lo + hi);
    const std::vector<Transform> centre = poses_along(model, a, b, mid);
    std::vector<double> moved(model.links().size(), 0.0);
    for (int k = 0; k <= 20; ++k) {
      const std::vector<Transform> poses = poses_along(model, a, b, lo + (hi - lo) * k / 20.0);
      for (std::size_t l = 0; l < poses.size(); ++l) {
        for (const CollisionElement& e : model.links()[l].collision) {
          for (const Vec3& v : e.mesh->vertices) moved[l] = std::max(moved[l], (poses[l] * (e.origin * v) - centre[l] * (e.origin * v)).norm());
        }
      }
    }
    for (std::size_t l = 0; l < moved.size(); ++l) {
      if (moved[l] < 1e-6) continue;  // a link the motion does not move
      const double growth = scene.link_growth(static_cast<int>(l), a.data(), b.data(), lo, hi);
      ASSERT_LE(moved[l], growth) << model.links()[l].name << " case " << i;
      // Distances do not depend on where the robot stands: the same bound with its root moved.
      ASSERT_NEAR(placed.link_growth(static_cast<int>(l), a.data(), b.data(), lo, hi), growth, 1e-9 * (1.0 + growth));
      ours.push_back(moved[l] / growth);
      chain.push_back(moved[l] / (checker.link_speed(static_cast<int>(l), a.data(), b.data()) * 0.5 * (hi - lo)));
    }
  }
  auto median_of = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double median = median_of(ours), chain_median = median_of(chain);
  std::cout << ours.size() << " link intervals: sampled displacement / growth, median " << median << " (the chain's length: "
            << chain_median << ")\n";
  EXPECT_GT(median, 0.65);  // 0.77 on panda (its chain-length bound: 0.33)
  EXPECT_GT(median, 2.0 * chain_median);
}

// The links above `link`, itself first, up to the root.
std::vector<int> chain_of(const RobotModel& model, int link) {
  std::vector<int> out{link};
  for (bool moved = true; moved;) {
    moved = false;
    for (const RobotJoint& j : model.joints()) {
      if (j.child_link == out.back()) {
        out.push_back(j.parent_link);
        moved = true;
        break;
      }
    }
  }
  return out;
}

// The same for a self pair in the frame of the two links' deepest common ancestor, where the
// joints above it move neither: the largest displacement of a vertex of each link there, summed,
// bounds how far their distance can fall, and stays within the pair's growth, though only the
// joints between the two links count.
TEST(SceneChecker, PairGrowthHoldsEveryVertexInTheCommonAncestorsFrame) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const SceneChecker scene(checker, std::make_shared<const Environment>(0.05));
  std::mt19937_64 rng(19);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double tightest = 0.0, saved = 0.0;
  for (int i = 0; i < test::sized(60); ++i) {
    const std::vector<double> a = random_configuration(model, rng), b = random_configuration(model, rng);
    const double lo = unit(rng), hi = lo + (1.0 - lo) * unit(rng);
    auto at = [&](double s) { return poses_along(model, a, b, s); };
    const std::vector<Transform> centre = at(0.5 * (lo + hi));
    std::vector<std::vector<Transform>> samples;
    for (int k = 0; k <= 10; ++k) samples.push_back(at(lo + (hi - lo) * k / 10.0));
    for (std::size_t p = 0; p < checker.checked_pairs().size(); ++p) {
      const auto [la, lb] = checker.checked_pairs()[p];
      const std::vector<int> up_a = chain_of(model, la), up_b = chain_of(model, lb);
      const int common = *std::find_if(up_a.begin(), up_a.end(), [&](int l) { return std::count(up_b.begin(), up_b.end(), l) > 0; });
      const double growth = scene.pair_growth(p, a.data(), b.data(), lo, hi);
      const double own = scene.link_growth(la, a.data(), b.data(), lo, hi) + scene.link_growth(lb, a.data(), b.data(), lo, hi);
      saved = std::max(saved, own / std::max(growth, 1e-12));
      for (const std::vector<Transform>& poses : samples) {
        double moved = 0.0;
        for (const int link : {la, lb}) {
          double farthest = 0.0;
          for (const CollisionElement& e : model.links()[link].collision) {
            for (const Vec3& v : e.mesh->vertices) {
              const Vec3 now = poses[common].inverse() * (poses[link] * (e.origin * v));
              const Vec3 then = centre[common].inverse() * (centre[link] * (e.origin * v));
              farthest = std::max(farthest, (now - then).norm());
            }
          }
          moved += farthest;
        }
        ASSERT_LE(moved, growth) << "pair " << p << " case " << i;
        if (growth > 0) tightest = std::max(tightest, moved / growth);
      }
    }
  }
  std::cout << "largest relative displacement / pair growth: " << tightest << "; the links' own growths sum to up to "
            << saved << " times as much\n";
  EXPECT_GT(tightest, 0.05);
  EXPECT_GT(saved, 2.0);  // the relative bound is much tighter for some pair
}

// Motions like a planner's edges between free states: free answers are free along a dense
// sweep (exact, every 2e-3 of the way); colliding answers collide where they say (at 1 cm:
// within 1 cm); at tolerance 0 the answers equal the checker's own certified check_motion.
TEST(SceneChecker, CertifiedMotionsHoldOnADenseSweep) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  std::mt19937_64 rng(13);
  std::size_t motions = 0, free_motions = 0, earliest = 0;
  double earliest_reach = 0.0;  // last valid / colliding fraction, summed
  std::size_t earliest_intervals = 0;
  for (int scene = 0; scene < 2; ++scene) {
    const auto env = std::make_shared<const Environment>(test::generate_scene(11, 10 + scene).environment());
    for (const double tolerance : {0.0, 0.01}) {
      SceneCheckOptions options;
      options.tolerance = tolerance;
      const SceneChecker fast(checker, env, options);
      std::vector<std::vector<double>> free;
      while (free.size() < 12) {
        const std::vector<double> q = random_configuration(checker.model(), rng);
        if (!exact_collides(checker, q.data(), *env)) free.push_back(q);
      }
      for (std::size_t i = 0; i + 1 < free.size(); ++i, ++motions) {
        std::vector<double> b = free[i];
        for (std::size_t j = 0; j < b.size(); ++j) b[j] += 0.4 * (free[i + 1][j] - free[i][j]);
        const MotionResult r = fast.check_motion(free[i].data(), b.data());
        ASSERT_TRUE(r.certified) << r.message;
        if (tolerance == 0.0) {
          MotionRequest request;  // conservative advancement, exact: another algorithm
          EXPECT_EQ(test::advancement_motion(checker, free[i].data(), b.data(), *env, request).valid, r.valid) << "motion " << i;
        }
        auto state = [&](double s) {
          std::vector<double> q(b.size());
          for (std::size_t j = 0; j < q.size(); ++j) q[j] = free[i][j] + s * (b[j] - free[i][j]);
          return q;
        };
        if (r.valid) {
          ++free_motions;
          for (int k = 0; k <= 500; ++k) {
            ASSERT_FALSE(exact_collides(checker, state(k / 500.0).data(), *env)) << "motion " << i << " at " << k;
          }
        } else {
          const std::vector<double> q = state(r.colliding_fraction);
          EXPECT_LE(exact_clearance(checker, q.data(), *env), tolerance + 2e-5 + 1e-9) << "motion " << i;  // within twice min_clearance
          EXPECT_LE(r.last_valid_fraction, r.colliding_fraction);
          // Looking for the earliest collision (what a planner's last valid state needs): the same
          // answer, a collision where it says, and free all the way up to the last valid fraction.
          const MotionResult e = fast.check_motion(free[i].data(), b.data(), true);
          ASSERT_FALSE(e.valid);
          // (Exact booleans with the links padded by that much: a distance query this close to a
          // contact takes most of a second.)
          EXPECT_TRUE(exact_collides(padded(tolerance + 2e-5 + 1e-9), state(e.colliding_fraction).data(), *env)) << "motion " << i;
          EXPECT_LE(e.last_valid_fraction, e.colliding_fraction);
          EXPECT_GE(e.last_valid_fraction, e.colliding_fraction - 1e-3);
          earliest_intervals += e.states_checked;
          for (int k = 0; k <= 200; ++k) {
            ASSERT_FALSE(exact_collides(checker, state(e.last_valid_fraction * k / 200.0).data(), *env)) << "motion " << i;
          }
          earliest_reach += e.last_valid_fraction / std::max(e.colliding_fraction, 1e-12);
          ++earliest;
        }
      }
    }
  }
  std::cout << motions << " motions, " << free_motions << " free; the earliest collision's last valid fraction reaches "
            << earliest_reach / std::max<std::size_t>(earliest, 1) << " of the way to it on average, in "
            << earliest_intervals << " intervals for " << earliest << " motions\n";
  EXPECT_GT(earliest_reach / std::max<std::size_t>(earliest, 1), 0.5);
  EXPECT_GT(free_motions, 0u);
  EXPECT_LT(free_motions, motions);
}

// Both of pr2's arms moving at once among a table, a cabinet and shelves on each side: an
// interval whose pending components read only some links poses only those (the others keep the
// poses of an earlier interval), so a motion's answers must still be conservative advancement's
// at tolerance 0, and a free answer at 1 cm free on a dense sweep.
TEST(SceneChecker, MotionsOfBothOfPr2sArmsAnswerAsAdvancement) {
  BVH_REQUIRE_ROBOTS();
  CheckerOptions options;  // proxy levels as a planner's checker has them (the finest left out: its build)
  options.proxy_levels = {0.01, 0.02};
  const CollisionChecker checker = test::load_as_moveit("pr2", options);
  const RobotModel& model = checker.model();
  Vec3 target;
  const auto env = std::make_shared<const Environment>(test::pr2_scene(5, 3, &target).environment());
  std::vector<double> base(model.variable_count(), 0.0);
  base[static_cast<std::size_t>(model.joints()[model.joint_index("torso_lift_joint")].variable)] = 0.15;
  std::vector<const RobotJoint*> arms;
  for (const RobotJoint& j : model.joints()) {
    const bool arm = j.name.find("_shoulder_") != std::string::npos || j.name.find("_upper_arm_roll") != std::string::npos ||
                     j.name.find("_elbow_flex") != std::string::npos || j.name.find("_forearm_roll") != std::string::npos ||
                     j.name.find("_wrist_") != std::string::npos;
    if (arm && j.variable >= 0 && j.mimic < 0) arms.push_back(&j);
  }
  ASSERT_EQ(arms.size(), 14u);
  std::mt19937_64 rng(61);
  auto draw = [&] {
    std::vector<double> q = base;
    for (const RobotJoint* j : arms) {
      q[static_cast<std::size_t>(j->variable)] = std::uniform_real_distribution<double>(j->bounded ? j->lower : -M_PI, j->bounded ? j->upper : M_PI)(rng);
    }
    return q;
  };
  std::vector<std::vector<double>> free;
  while (free.size() < static_cast<std::size_t>(test::sized(13))) {
    const std::vector<double> q = draw();
    if (!exact_collides(checker, q.data(), *env)) free.push_back(q);
  }
  int free_motions = 0, motions = 0;
  for (const double tolerance : {0.0, 0.01}) {
    SceneCheckOptions scene_options;
    scene_options.tolerance = tolerance;
    const SceneChecker fast(checker, env, scene_options);
    for (std::size_t i = 0; i + 1 < free.size(); ++i, ++motions) {
      std::vector<double> b = free[i];
      // A short motion then a longer one: some free, some colliding (three states under the
      // sanitizers make one of each a tolerance).
      const double reach = i % 2 == 0 ? 0.03 : 0.2;
      for (std::size_t j = 0; j < b.size(); ++j) b[j] += reach * (free[i + 1][j] - free[i][j]);
      const MotionResult r = fast.check_motion(free[i].data(), b.data());
      ASSERT_TRUE(r.certified) << r.message;
      if (tolerance == 0.0) {
        MotionRequest request;  // conservative advancement, exact: another algorithm
        EXPECT_EQ(test::advancement_motion(checker, free[i].data(), b.data(), *env, request).valid, r.valid) << "motion " << i;
      }
      auto state = [&](double f) {
        std::vector<double> q(b.size());
        for (std::size_t j = 0; j < q.size(); ++j) q[j] = free[i][j] + f * (b[j] - free[i][j]);
        return q;
      };
      if (r.valid) {
        ++free_motions;
        for (int k = 0; k <= 200; ++k) ASSERT_FALSE(exact_collides(checker, state(k / 200.0).data(), *env)) << "motion " << i << " at " << k;
        continue;
      }
      // The earliest collision (intervals depth first, left first: the poses kept from an
      // interval far along the motion): a collision where it says, free up to the last valid state.
      const MotionResult e = fast.check_motion(free[i].data(), b.data(), true);
      ASSERT_FALSE(e.valid);
      EXPECT_LE(exact_clearance(checker, state(e.colliding_fraction).data(), *env), tolerance + 2e-5 + 1e-9) << "motion " << i;
      for (int k = 0; k <= 50; ++k) {
        ASSERT_FALSE(exact_collides(checker, state(e.last_valid_fraction * k / 50.0).data(), *env)) << "motion " << i << " at " << k;
      }
    }
  }
  std::cout << motions << " motions of both arms, " << free_motions << " free\n";
  EXPECT_GT(free_motions, 0);
}

// Panda's straight motion from its ready pose (the fingers half open): joint 1 turned by 0.02 rad,
// joint 4 to `joint4` when given; its ends and its state at fraction s.
struct ReadyMotion {
  std::vector<double> a, b;
  explicit ReadyMotion(const RobotModel& model, std::optional<double> joint4 = std::nullopt) : a(model.variable_count(), 0.02) {
    auto variable = [&](const std::string& joint) { return static_cast<std::size_t>(model.joints()[model.joint_index(joint)].variable); };
    const double ready[] = {0.0, -0.785, 0.0, -2.356, 0.0, 1.571, 0.785};
    for (int j = 0; j < 7; ++j) a[variable("panda_joint" + std::to_string(j + 1))] = ready[j];
    b = a;
    b[variable("panda_joint1")] += 0.02;
    if (joint4) b[variable("panda_joint4")] = *joint4;
  }
  std::vector<double> at(double s) const {
    std::vector<double> q(a.size());
    for (std::size_t j = 0; j < q.size(); ++j) q[j] = a[j] + s * (b[j] - a[j]);
    return q;
  }
};

// Within one interval, a link that barely moves and lies just inside its growth of an obstacle
// frees a stretch around the midpoint by its exact distance (it cannot close that gap sooner).
// The stretch holds only for the components that were measured: here the hand swings through a
// thin bar inside it (a large joint 4 motion, far beyond any piece's growth), while link 1, turned
// a little by joint 1, grazes a box at the base. The collision with the bar must be found.
TEST(SceneChecker, AStretchFreedByOneLinkDoesNotFreeAFasterOne) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const ReadyMotion motion(model, -0.6);
  const std::vector<double>& a = motion.a;
  const std::vector<double>& b = motion.b;
  auto state = [&](double s) { return motion.at(s); };
  const int link1 = model.link_index("panda_link1"), hand = model.link_index("panda_hand");
  const auto empty = std::make_shared<const Environment>(Environment(0.05));
  const SceneChecker bare(checker, empty);
  const double slow = bare.link_growth(link1, a.data(), b.data(), 0.0, 1.0);
  const double fast = bare.link_growth(hand, a.data(), b.data(), 0.0, 1.0);
  // A 2 cm box beside link 1 at the midpoint, 0.6 of link 1's growth away from it.
  const std::vector<Transform> mid = poses_along(model, a, b, 0.5);
  auto box_at = [&](double t) {
    Environment world(0.05);
    world.add_object("base_box", ObjectShape::box({0.02, 0.02, 0.02}), Transform::Translation(mid[link1].t + Vec3(0.0, -t, -0.05)));
    return world;
  };
  auto distance_at = [&](const Environment& world, double s) {
    EnvironmentRequest request;
    request.distance = true;
    request.contacts = false;
    const EnvironmentResult r = checker.check_environment(state(s).data(), world, request);
    return std::make_pair(r.collision ? 0.0 : r.min_distance, r.closest_link);
  };
  double lo = 0.0, hi = 0.5;
  for (int i = 0; i < 60; ++i) {
    const double t = 0.5 * (lo + hi);
    (distance_at(box_at(t), 0.5).first < 0.9 * slow ? lo : hi) = t;
  }
  Environment world = box_at(hi);
  const auto [gap, nearest] = distance_at(world, 0.5);
  ASSERT_EQ(nearest, link1);
  ASSERT_GT(gap, 0.0);
  ASSERT_LT(gap, slow);     // link 1 fails its grown test: its exact distance frees a stretch
  ASSERT_GT(fast, 0.4);     // the hand's growth over the motion: far beyond any piece's
  const std::vector<Transform> late = poses_along(model, a, b, 0.76);
  world.add_object("bar", ObjectShape::box({0.01, 0.01, 0.01}), Transform::Translation(late[hand].t));
  const auto env = std::make_shared<const Environment>(world);
  int first = -1;
  for (int k = 0; k <= 1000 && first < 0; ++k) first = exact_collides(checker, state(k / 1000.0).data(), *env) ? k : -1;
  ASSERT_GT(first, 500);  // free at the midpoint, colliding inside the stretch link 1 frees
  ASSERT_LT(first / 1000.0, 0.5 + 0.5 * gap / slow);
  const SceneChecker scene(checker, env);
  const MotionResult r = scene.check_motion(a.data(), b.data());
  EXPECT_FALSE(r.valid);
  const MotionResult e = scene.check_motion(a.data(), b.data(), true);
  ASSERT_FALSE(e.valid);
  EXPECT_TRUE(exact_collides(padded(2e-5 + 1e-9), state(e.colliding_fraction).data(), *env)) << e.colliding_fraction;
  EXPECT_GE(e.last_valid_fraction, first / 1000.0 - 1e-3 - 1e-3);
  std::cout << "growth over the motion: link 1 " << slow << " m, the hand " << fast << " m; link 1 " << gap
            << " m from its box; the bar met from " << first / 1000.0 << ", found at " << r.colliding_fraction << "\n";
}

// The same for one link near two objects: link 1's exact distance to the box beside it frees a
// stretch for that box only; a second box, met by link 1 inside that stretch, must still be found,
// whichever of the two the object grid offers first. (Found by a search over small boxes around
// link 1: one free at the midpoint and met within the stretch.)
TEST(SceneChecker, AStretchFreedByOneObjectDoesNotFreeAnother) {
  BVH_REQUIRE_ROBOTS();
  const CollisionChecker& checker = panda();
  const RobotModel& model = checker.model();
  const ReadyMotion motion(model);
  const std::vector<double>& a = motion.a;
  const std::vector<double>& b = motion.b;
  auto state = [&](double s) { return motion.at(s); };
  const int link1 = model.link_index("panda_link1");
  const auto empty = std::make_shared<const Environment>(Environment(0.05));
  const double slow = SceneChecker(checker, empty).link_growth(link1, a.data(), b.data(), 0.0, 1.0);
  const std::vector<Transform> mid = poses_along(model, a, b, 0.5);
  auto link1_distance = [&](const Environment& world, double s) {
    EnvironmentRequest request;
    request.distance = true;
    request.contacts = false;
    const EnvironmentResult r = checker.check_environment(state(s).data(), world, request);
    return r.collision ? 0.0 : r.min_distance;
  };
  // The first box 0.6 of link 1's growth from it at the midpoint, on one side.
  auto first_box = [&](Environment& world, double t) {
    world.add_object("side", ObjectShape::box({0.02, 0.02, 0.02}), Transform::Translation(mid[link1].t + Vec3(0.0, -t, -0.05)));
  };
  double lo = 0.0, hi = 0.5;
  for (int i = 0; i < 60; ++i) {
    const double t = 0.5 * (lo + hi);
    Environment world(0.05);
    first_box(world, t);
    (link1_distance(world, 0.5) < 0.6 * slow ? lo : hi) = t;
  }
  Environment side(0.05);
  first_box(side, hi);
  const double gap = link1_distance(side, 0.5);
  ASSERT_GT(gap, 0.0);
  ASSERT_LT(gap, slow);
  // A 4 mm box around link 1, free at the midpoint and met inside the stretch the first frees.
  auto add_second = [&](Environment& world, const Vec3& at) {
    world.add_object("bar", ObjectShape::box({0.004, 0.004, 0.004}), Transform::Translation(at));
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-0.12, 0.12);
  for (const char* order : {"side box, bar", "bar, side box"}) {
    const bool side_first = order[0] == 's';
    std::optional<Vec3> found;
    for (int tries = 0; tries < 4000 && !found; ++tries) {
      const Vec3 at = mid[link1].t + Vec3(u(rng), u(rng), u(rng));
      Environment world(0.05);
      add_second(world, at);
      if (link1_distance(world, 0.5) <= 0.0 || link1_distance(world, 0.5) > 0.5 * gap) continue;
      for (int k = 1; k <= 40 && !found; ++k) {
        if (link1_distance(world, 0.5 + k / 40.0 * 0.45 * gap / slow) <= 0.0) found = at;
      }
    }
    ASSERT_TRUE(found.has_value()) << order;
    Environment world(0.05);
    if (side_first) first_box(world, hi);
    add_second(world, *found);
    if (!side_first) first_box(world, hi);
    const auto env = std::make_shared<const Environment>(world);
    const SceneChecker scene(checker, env);
    EXPECT_FALSE(scene.check_motion(a.data(), b.data()).valid) << order;
    const MotionResult e = scene.check_motion(a.data(), b.data(), true);
    ASSERT_FALSE(e.valid) << order;
    EXPECT_TRUE(exact_collides(padded(2e-5 + 1e-9), state(e.colliding_fraction).data(), *env)) << e.colliding_fraction;
    // Free all the way to the last valid state (a planner goes there).
    for (int k = 0; k <= 200; ++k) {
      ASSERT_FALSE(exact_collides(checker, state(e.last_valid_fraction * k / 200.0).data(), *env))
          << order << ": last valid " << e.last_valid_fraction;
    }
  }
}

}  // namespace
}  // namespace bvh_collision
