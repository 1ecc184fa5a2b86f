// Self-collision against FCL as the oracle: the same shapes (FCL BVHModel<OBBRSS> of the very
// meshes and of URDF boxes, FCL's own primitives for URDF spheres and cylinders), the same
// allowed-collision matrix, random configurations.
#include <gtest/gtest.h>

#include <map>

#include <fstream>
#include <algorithm>
#include <random>
#include <set>
#include <sstream>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/robot/robot_description.h"
#include "fcl_oracle.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

struct Fixture {
  std::unique_ptr<CollisionChecker> checker;
  Srdf srdf;
  // Per link: FCL objects (built once; moved per configuration) and their origins in the link frame.
  std::vector<std::vector<std::pair<std::shared_ptr<fcl::CollisionObjectd>, Transform>>> fcl_shapes;
};

Fixture make_fixture(const std::string& robot) {
  // "demo": the package's own arm, made of cylinders, spheres and boxes.
  const bool demo = robot == "demo";
  const std::string dir = demo ? test::source_dir() + "/urdf" : test::robots_dir() + "/" + robot;
  const std::string urdf = demo ? dir + "/demo_arm.urdf" : dir + "/robot.urdf";
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(urdf), PackageResolver({dir}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  Fixture f;
  if (std::ifstream in(dir + "/robot.srdf"); in) {
    std::ostringstream s;
    s << in.rdbuf();
    f.srdf = parse_srdf(s.str(), &model);
    apply_srdf(f.srdf, model, acm);
  }
  f.fcl_shapes.resize(model.links().size());
  for (std::size_t l = 0; l < model.links().size(); ++l) {
    for (const CollisionElement& e : model.links()[l].collision) {
      std::shared_ptr<fcl::CollisionGeometryd> g;
      if (e.shape == CollisionElement::Shape::kSphere) {
        g = std::make_shared<fcl::Sphered>(e.radius);
      } else if (e.shape == CollisionElement::Shape::kCylinder) {
        g = std::make_shared<fcl::Cylinderd>(e.radius, e.length);
      } else {  // meshes, and boxes as their 12 exact triangles (a surface, as our solids=false)
        g = test::fcl_model<fcl::OBBRSSd>(*e.mesh);
      }
      f.fcl_shapes[l].emplace_back(std::make_shared<fcl::CollisionObjectd>(g), e.origin);
    }
  }
  f.checker = std::make_unique<CollisionChecker>(std::move(model), std::move(acm));
  return f;
}

// FCL's answer over the checker's own pair list: colliding pairs and minimum distance.
std::set<std::pair<int, int>> fcl_pairs(const Fixture& f, const std::vector<Transform>& poses, bool want_distance,
                                        double* min_distance) {
  for (std::size_t l = 0; l < f.fcl_shapes.size(); ++l) {
    for (const auto& [object, origin] : f.fcl_shapes[l]) {
      object->setTransform(test::fcl_transform(poses[l] * origin));
      object->computeAABB();
    }
  }
  std::set<std::pair<int, int>> hits;
  // Shape pairs with FCL's own AABB distance, nearest first: the distance search below prunes
  // with FCL's bounds only, so the oracle stays independent of the code under test.
  struct Candidate {
    double aabb_distance;
    const fcl::CollisionObjectd *xa, *xb;
    int a, b;
  };
  std::vector<Candidate> candidates;
  for (const auto& [a, b] : f.checker->checked_pairs()) {
    for (const auto& sa : f.fcl_shapes[a]) {
      for (const auto& sb : f.fcl_shapes[b]) {
        candidates.push_back({sa.first->getAABB().distance(sb.first->getAABB()), sa.first.get(), sb.first.get(), a, b});
      }
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& x, const Candidate& y) { return x.aabb_distance < y.aabb_distance; });
  double best = std::numeric_limits<double>::infinity();
  for (const Candidate& c : candidates) {
    if (c.aabb_distance == 0.0) {  // FCL's broad phase: only overlapping boxes can collide
      fcl::CollisionRequestd creq;
      fcl::CollisionResultd cres;
      fcl::collide(c.xa, c.xb, creq, cres);
      if (cres.isCollision()) {
        hits.insert({c.a, c.b});
        best = 0.0;
      }
    }
    if (want_distance && c.aabb_distance < best) {
      fcl::DistanceRequestd dreq;
      fcl::DistanceResultd dres;
      fcl::distance(c.xa, c.xb, dreq, dres);
      best = std::min(best, std::max(0.0, dres.min_distance));
    }
  }
  if (min_distance) *min_distance = best;
  return hits;
}

// How far p (root frame) is from link `link`'s primitive elements (closed forms, independent of
// the checker): NaN when the link has a mesh element, which this cannot measure.
double primitive_link_distance(const RobotModel& m, const std::vector<Transform>& poses, int link, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const CollisionElement& e : m.links()[link].collision) {
    const Vec3 q = (poses[link] * e.origin).inverse() * p;
    switch (e.shape) {
      case CollisionElement::Shape::kSphere: best = std::min(best, std::max(0.0, q.norm() - e.radius)); break;
      case CollisionElement::Shape::kCylinder:
        best = std::min(best, std::hypot(std::max(0.0, std::hypot(q.x(), q.y()) - e.radius),
                                         std::max(0.0, std::abs(q.z()) - 0.5 * e.length)));
        break;
      case CollisionElement::Shape::kBox:
        best = std::min(best, (q.cwiseAbs() - 0.5 * e.size).cwiseMax(0.0).norm());
        break;
      case CollisionElement::Shape::kMesh:
      case CollisionElement::Shape::kCapsule:  // not in URDF
      case CollisionElement::Shape::kCone: return std::numeric_limits<double>::quiet_NaN();
    }
  }
  return best;
}

class SelfCollision : public ::testing::TestWithParam<const char*> {};

// One fixture per robot for the whole run: building the checker and FCL's models is most of the
// time under the sanitizers, and every test only reads them (FCL objects are moved per state).
const Fixture& fixture(const std::string& robot) {
  static std::map<std::string, Fixture> built;
  auto it = built.find(robot);
  if (it == built.end()) it = built.emplace(robot, make_fixture(robot)).first;
  return it->second;
}

TEST_P(SelfCollision, CollidingPairsAndDistanceEqualFcl) {
  BVH_REQUIRE_ROBOTS();
  const Fixture& f = fixture(GetParam());
  const RobotModel& m = f.checker->model();
  std::mt19937_64 rng(17);
  std::vector<Transform> poses;
  int colliding = 0, fcl_above_truth = 0;
  // All 2000 agreed in a one-off run (109 s); a quarter under the sanitizers (test::sized).
  const int kConfigurations = test::sized(2000), kDistanceConfigurations = test::sized(500);
  for (int i = 0; i < kConfigurations; ++i) {
    const std::vector<double> state = random_configuration(m, rng);
    forward_kinematics(m, state.data(), poses);
    const bool with_distance = i < kDistanceConfigurations;
    double fcl_distance = 0.0;
    const auto expected = fcl_pairs(f, poses, with_distance, &fcl_distance);
    SelfCollisionRequest request;
    request.all_pairs = true;
    request.solids = false;  // FCL treats meshes as surfaces
    request.distance = with_distance;
    const SelfCollisionResult r = f.checker->check_self(state.data(), request);
    const std::set<std::pair<int, int>> found(r.colliding_pairs.begin(), r.colliding_pairs.end());
    ASSERT_EQ(found, expected) << GetParam() << " configuration " << i;
    SelfCollisionRequest boolean;
    boolean.solids = false;
    ASSERT_EQ(f.checker->check_self(state.data(), boolean).collision, !found.empty()) << "boolean agrees";
    if (with_distance && std::abs(r.min_distance - fcl_distance) > 1e-6) {
      // FCL's primitive pairs (cylinders) go through GJK with a 1e-6 tolerance and may report
      // more than the truth: accepted only when ours is below FCL's and both our witnesses lie on
      // their links' primitives (closed forms), which proves the truth is at most ours.
      const double on_a = primitive_link_distance(m, poses, r.closest_a, r.point_a);
      const double on_b = primitive_link_distance(m, poses, r.closest_b, r.point_b);
      ASSERT_TRUE(r.min_distance < fcl_distance && on_a <= 1e-9 && on_b <= 1e-9)
          << GetParam() << " configuration " << i << ": ours " << r.min_distance << ", FCL " << fcl_distance
          << ", witnesses off their links by " << on_a << " and " << on_b;
      ++fcl_above_truth;
    }
    if (with_distance) {
      // The witnesses are the reported distance apart (whether the convex hulls or the BVH
      // traversal settled it) and belong to a checked pair.
      if (std::isfinite(r.min_distance)) {
        ASSERT_NEAR((r.point_a - r.point_b).norm(), r.min_distance, 1e-9) << GetParam() << " configuration " << i;
        ASSERT_FALSE(f.checker->acm().allowed(r.closest_a, r.closest_b));
      }
    }
    colliding += !expected.empty();
  }
  std::cout << GetParam() << ": " << colliding << " of " << kConfigurations << " configurations collide, "
            << f.checker->checked_pairs().size() << " checked pairs; FCL's distance above the witnessed truth in "
            << fcl_above_truth << " of " << kDistanceConfigurations << "\n";
}

// The SRDF's rest states (home, ready, ...) are collision-free, solids included; every named
// state (with unnamed joints at 0, clamped into their limits) is answered as FCL answers it.
TEST_P(SelfCollision, SrdfNamedStates) {
  BVH_REQUIRE_ROBOTS();
  const Fixture& f = fixture(GetParam());
  const RobotModel& m = f.checker->model();
  const std::set<std::string> rest = {"home", "ready", "all-zeros", "default", "up", "extended", "tuck_left_arm", "tuck_right_arm"};
  int rest_states = 0;
  std::vector<Transform> poses;
  for (const auto& [name, values] : f.srdf.group_states) {
    std::vector<double> state(m.variable_count(), 0.0);
    for (std::size_t v = 0; v < state.size(); ++v) {
      const RobotJoint& j = m.joints()[m.joint_index(m.variable_names()[v])];
      if (j.bounded) state[v] = std::clamp(0.0, j.lower, j.upper);
    }
    for (const auto& [joint, value] : values) {
      const int j = m.joint_index(joint);
      if (j >= 0 && m.joints()[j].variable >= 0) state[m.joints()[j].variable] = value.values.at(0);
    }
    SelfCollisionRequest request;
    request.all_pairs = true;
    const SelfCollisionResult r = f.checker->check_self(state.data(), request);
    std::string pairs;
    for (const auto& [a, b] : r.colliding_pairs) pairs += m.links()[a].name + ":" + m.links()[b].name + " ";
    if (rest.count(name)) {
      ++rest_states;
      EXPECT_FALSE(r.collision) << GetParam() << " state '" << name << "' collides: " << pairs;
    }
    forward_kinematics(m, state.data(), poses);
    const auto fcl = fcl_pairs(f, poses, false, nullptr);
    const std::set<std::pair<int, int>> ours(r.colliding_pairs.begin(), r.colliding_pairs.end());
    EXPECT_EQ(ours, fcl)
        << GetParam() << " state '" << name << "': ours " << pairs;
  }
  if (!f.srdf.group_states.empty()) {
    EXPECT_GT(rest_states, 0) << "no rest state found among the SRDF's states";
  }
}

// Batch answers equal single answers (and the batch uses every core).
TEST_P(SelfCollision, BatchEqualsSingle) {
  BVH_REQUIRE_ROBOTS();
  const Fixture& f = fixture(GetParam());
  const RobotModel& m = f.checker->model();
  std::mt19937_64 rng(23);
  std::vector<double> states;
  for (int i = 0; i < 300; ++i) {
    const auto s = random_configuration(m, rng);
    states.insert(states.end(), s.begin(), s.end());
  }
  const std::vector<bool> batch = f.checker->check_self_batch(states.data(), 300);
  ASSERT_EQ(batch.size(), 300u);
  for (int i = 0; i < 300; ++i) {
    ASSERT_EQ(batch[i], f.checker->check_self(states.data() + i * m.variable_count()).collision) << i;
  }
}

// Distance with a tolerance: never below the exact distance, at most the tolerance above it.
TEST_P(SelfCollision, DistanceToleranceBoundsTheError) {
  BVH_REQUIRE_ROBOTS();
  const Fixture& f = fixture(GetParam());
  std::mt19937_64 rng(31);
  SelfCollisionRequest exact;
  exact.distance = true;
  for (int i = 0; i < test::sized(150); ++i) {
    const auto s = random_configuration(f.checker->model(), rng);
    const SelfCollisionResult truth = f.checker->check_self(s.data(), exact);
    for (const double tolerance : {0.001, 0.005, 0.02, 0.1}) {
      SelfCollisionRequest loose = exact;
      loose.tolerance = tolerance;
      const SelfCollisionResult r = f.checker->check_self(s.data(), loose);
      ASSERT_GE(r.min_distance, truth.min_distance) << "state " << i << " tolerance " << tolerance;
      ASSERT_LE(r.min_distance, truth.min_distance + tolerance) << "state " << i << " tolerance " << tolerance;
      // The collision answer follows docs/design.md: never a miss, "collision" only within the tolerance.
      if (truth.collision) {
        ASSERT_TRUE(r.collision) << i;
      }
      if (r.collision) {
        ASSERT_LE(truth.min_distance, tolerance) << i;
      }
      if (std::isfinite(r.min_distance) && r.min_distance > 0) {  // the witnesses are that far apart
        ASSERT_NEAR((r.point_a - r.point_b).norm(), r.min_distance, 1e-9) << i;
      }
    }
  }
}

// pairs_moved_by against brute force: a pair is left out exactly when random changes of the
// variables never change the two links' relative pose.
TEST_P(SelfCollision, PairsMovedByAreThePairsWhoseRelativePoseChanges) {
  BVH_REQUIRE_ROBOTS();
  const Fixture& f = fixture(GetParam());
  const RobotModel& m = f.checker->model();
  std::mt19937_64 rng(37);
  const auto& pairs = f.checker->checked_pairs();
  for (int trial = 0; trial < 6; ++trial) {
    std::vector<int> group;  // a random subset of the variables (the last ones on trial 0: a wrist)
    for (int v = 0; v < static_cast<int>(m.variable_count()); ++v) {
      if (trial == 0 ? v + 3 >= static_cast<int>(m.variable_count()) : rng() % 3 == 0) group.push_back(v);
    }
    const std::vector<std::size_t> moved = f.checker->pairs_moved_by(group);
    const std::set<std::size_t> moved_set(moved.begin(), moved.end());
    ASSERT_EQ(moved_set.size(), moved.size());
    std::vector<char> changed(pairs.size(), 0);
    for (int k = 0; k < 8; ++k) {
      const auto base = random_configuration(m, rng);
      auto other = base;
      const auto fresh = random_configuration(m, rng);
      for (const int v : group) other[v] = fresh[v];
      std::vector<Transform> pa, pb;
      forward_kinematics(m, base.data(), pa);
      forward_kinematics(m, other.data(), pb);
      for (std::size_t p = 0; p < pairs.size(); ++p) {
        const auto [a, b] = pairs[p];
        const Transform ra = pa[a].inverse() * pa[b], rb = pb[a].inverse() * pb[b];
        const double gap = (ra.t - rb.t).norm() + (ra.R - rb.R).norm();
        if (!moved_set.count(p)) {
          ASSERT_LT(gap, 1e-9) << m.links()[a].name << ":" << m.links()[b].name;
        }
        changed[p] |= gap > 1e-9;
      }
    }
    for (const std::size_t p : moved) {
      EXPECT_TRUE(changed[p]) << m.links()[pairs[p].first].name << ":" << m.links()[pairs[p].second].name;
    }
  }
  EXPECT_TRUE(f.checker->pairs_moved_by({}).empty());
  EXPECT_THROW(f.checker->pairs_moved_by({static_cast<int>(m.variable_count())}), std::out_of_range);
}

// Checking only the moved pairs, plus the rigid pairs once, gives the full answer.
TEST_P(SelfCollision, OnlyMovedPairsPlusRigidPairsOnceEqualsTheFullCheck) {
  BVH_REQUIRE_ROBOTS();
  const Fixture& f = fixture(GetParam());
  const RobotModel& m = f.checker->model();
  std::mt19937_64 rng(41);
  std::vector<int> group;
  for (int v = static_cast<int>(m.variable_count()) / 2; v < static_cast<int>(m.variable_count()); ++v) group.push_back(v);
  const std::vector<std::size_t> moved = f.checker->pairs_moved_by(group);
  std::vector<std::size_t> rigid;
  for (std::size_t p = 0, k = 0; p < f.checker->checked_pairs().size(); ++p) {
    if (k < moved.size() && moved[k] == p) {
      ++k;
    } else {
      rigid.push_back(p);
    }
  }
  SelfCollisionRequest moved_only, rigid_only, distance;
  moved_only.only_pairs = &moved;
  rigid_only.only_pairs = &rigid;
  distance.distance = true;
  for (int i = 0; i < 20; ++i) {
    const auto base = random_configuration(m, rng);
    const bool rigid_hit = f.checker->check_self(base.data(), rigid_only).collision;
    for (int k = 0; k < 6; ++k) {
      auto s = base;
      const auto fresh = random_configuration(m, rng);
      for (const int v : group) s[v] = fresh[v];
      const bool full = f.checker->check_self(s.data()).collision;
      ASSERT_EQ(rigid_hit || f.checker->check_self(s.data(), moved_only).collision, full) << i << " " << k;
      SelfCollisionRequest d = distance;
      d.only_pairs = &moved;
      SelfCollisionRequest dr = distance;
      dr.only_pairs = &rigid;
      const double split = std::min(f.checker->check_self(s.data(), d).min_distance, f.checker->check_self(base.data(), dr).min_distance);
      ASSERT_EQ(split, f.checker->check_self(s.data(), distance).min_distance) << i << " " << k;
    }
  }
  const std::vector<std::size_t> bad = {f.checker->checked_pairs().size()};
  SelfCollisionRequest wrong;
  wrong.only_pairs = &bad;
  EXPECT_THROW(f.checker->check_self(std::vector<double>(m.variable_count(), 0.0).data(), wrong), std::out_of_range);
}

INSTANTIATE_TEST_SUITE_P(Robots, SelfCollision,
                         ::testing::Values("panda", "ur5e", "pr2", "abb_irb2400", "solo", "panda_capsules", "demo"));

// The demo robot folded onto itself: the reported pair is the one that meets; padding and
// tolerance behave as docs/design.md says.
TEST(SelfCollisionDemo, FoldedArmReportsTheRightPairAndPaddingWorks) {
  const std::string urdf_path = test::source_dir() + "/urdf/demo_arm.urdf";
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(urdf_path), PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  const CollisionChecker checker(std::move(model), std::move(acm));
  const RobotModel& m = checker.model();
  std::vector<double> state(m.variable_count(), 0.0);
  SelfCollisionRequest all;
  all.all_pairs = true;
  all.distance = true;
  const SelfCollisionResult home = checker.check_self(state.data(), all);
  EXPECT_FALSE(home.collision);
  EXPECT_GT(home.min_distance, 0.0);
  // Elbow (joint3) folded fully back: the forearm swings down into the upper arm's base.
  state[m.joints()[m.joint_index("joint3")].variable] = 2.6;
  state[m.joints()[m.joint_index("joint2")].variable] = 1.2;
  const SelfCollisionResult folded = checker.check_self(state.data(), all);
  ASSERT_TRUE(folded.collision);
  bool hand_or_wrist_hits_base_side = false;
  for (const auto& [a, b] : folded.colliding_pairs) {
    const std::string pair = m.links()[a].name + ":" + m.links()[b].name;
    hand_or_wrist_hits_base_side |= pair.find("link1") != std::string::npos || pair.find("base_link") != std::string::npos ||
                                    pair.find("link2") != std::string::npos;
  }
  EXPECT_TRUE(hand_or_wrist_hits_base_side);
  EXPECT_EQ(folded.min_distance, 0.0);
  // Padding: a free state whose distance d is known collides with padding just over d/2 per link.
  const double d = home.min_distance;
  CheckerOptions padded;
  padded.padding = 0.5 * d * 1.01;
  RobotModel model2 = RobotModel::from_urdf(*load_robot_description_file(urdf_path), PackageResolver({}));
  AllowedCollisionMatrix acm2 = AllowedCollisionMatrix::adjacent_links(model2);
  const CollisionChecker padded_checker(std::move(model2), std::move(acm2), padded);
  std::vector<double> zero(m.variable_count(), 0.0);
  EXPECT_TRUE(padded_checker.check_self(zero.data()).collision);
  // Tolerance: at most d may be reported, never a miss; below d it must stay free.
  SelfCollisionRequest tight;
  tight.tolerance = 0.9 * d;
  EXPECT_FALSE(checker.check_self(zero.data(), tight).collision);
}

}  // namespace
}  // namespace bvh_collision
