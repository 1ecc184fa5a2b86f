// URDF cylinders are exact shapes (docs/design.md: tolerance 0 is exact for primitives too).
// Two cylinder links on a prismatic joint are placed at known gaps, with dyadic sizes so that the
// gap 0 is exactly touching in doubles: the answers must be exact (touching collides; 1e-12 m
// apart is free) and the distance must be the gap. A circumscribing prism answers "collision"
// for every gap below its own error.
#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <string>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/robot/robot_description.h"

namespace bvh_collision {
namespace {

// Link "a" holds a cylinder (radius r, length l, axis z) at its origin; link "b" hangs from a
// prismatic joint along `axis` with `origin` (xyz, rpy) and holds the same cylinder, turned by
// `b_rpy`. The joint value is the gap in every case below.
std::string two_cylinders(const std::string& axis, const std::string& origin_xyz, const std::string& b_rpy) {
  std::ostringstream u;
  u << R"(<robot name="two_cylinders">
  <link name="a"><collision><geometry><cylinder radius="0.0625" length="0.25"/></geometry></collision></link>
  <joint name="slide" type="prismatic"><parent link="a"/><child link="b"/>
    <origin xyz=")" << origin_xyz << R"("/><axis xyz=")" << axis << R"("/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <link name="b"><collision><origin rpy=")" << b_rpy << R"("/>
    <geometry><cylinder radius="0.0625" length="0.25"/></geometry></collision></link>
</robot>)";
  return u.str();
}

CollisionChecker checker_for(const std::string& urdf) {
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(urdf), PackageResolver({}));
  AllowedCollisionMatrix acm(model.links().size());  // the two links are checked although adjacent
  return CollisionChecker(std::move(model), std::move(acm));
}

struct Placement {
  const char* name;
  std::string urdf;
};

class ExactCylinders : public ::testing::TestWithParam<int> {};

const Placement& placement(int i) {
  static const std::string quarter = [] {
    std::ostringstream o;
    o.precision(17);
    o << std::acos(-1.0) / 2;  // every digit: a rounded angle tilts b by more than the gaps tested
    return o.str();
  }();
  static const Placement kPlacements[] = {
      // Parallel axes, side against side along a line: the curved case.
      {"side by side", two_cylinders("1 0 0", "0.125 0 0", "0 0 0")},
      // Coaxial, cap against cap: flat faces.
      {"end to end", two_cylinders("0 0 1", "0 0 0.25", "0 0 0")},
      // Crossed axes (b along y), side against side at one point.
      {"crossed", two_cylinders("1 0 0", "0.125 0 0", quarter + " 0 0")},
      // b along x, its cap against a's side: a flat disc against a curved side along a segment.
      {"cap on side", two_cylinders("1 0 0", "0.1875 0 0", "0 " + quarter + " 0")},
  };
  return kPlacements[i];
}

TEST_P(ExactCylinders, GapsAreAnsweredExactly) {
  const Placement& p = placement(GetParam());
  const CollisionChecker checker = checker_for(p.urdf);
  // rpy of a quarter turn is not exact in doubles: the rotated cases touch up to its rounding
  // (about 1e-17 m here), far below the smallest gap tested.
  for (const double gap : {0.0, 1e-12, 4.5e-6, 2.9e-4, 0.01}) {
    const double q = gap;
    SelfCollisionRequest boolean;
    const bool collides = checker.check_self(&q, boolean).collision;
    EXPECT_EQ(collides, gap == 0.0) << p.name << ", gap " << gap;
    SelfCollisionRequest distance;
    distance.distance = true;
    const SelfCollisionResult d = checker.check_self(&q, distance);
    EXPECT_EQ(d.collision, gap == 0.0) << p.name << ", gap " << gap;
    EXPECT_NEAR(d.min_distance, gap, 2e-13 + 1e-9 * gap) << p.name << ", gap " << gap;
    if (std::isfinite(d.min_distance)) {
      EXPECT_NEAR((d.point_a - d.point_b).norm(), d.min_distance, 1e-12 + 1e-9 * gap) << p.name;
    }
  }
  // Overlapping by 1e-12 collides too, and padding counts from the true surface.
  const double overlap = -1e-12;
  EXPECT_TRUE(checker.check_self(&overlap).collision) << p.name;
}

TEST_P(ExactCylinders, PaddingAndToleranceCountFromTheTrueSurface) {
  const Placement& p = placement(GetParam());
  CheckerOptions options;
  options.padding = 1e-4;  // each link: 2e-4 for the pair
  RobotModel model = RobotModel::from_urdf(*parse_robot_description(p.urdf), PackageResolver({}));
  AllowedCollisionMatrix acm(model.links().size());
  const CollisionChecker checker(std::move(model), std::move(acm), options);
  for (const double gap : {1.9e-4, 2.1e-4}) {
    EXPECT_EQ(checker.check_self(&gap).collision, gap < 2e-4) << p.name << ", gap " << gap;
  }
  // With a tolerance, collision may be reported up to padding + tolerance, never beyond.
  SelfCollisionRequest tolerant;
  tolerant.tolerance = 1e-4;
  const double far = 3.01e-4;
  EXPECT_FALSE(checker.check_self(&far, tolerant).collision) << p.name;
}

INSTANTIATE_TEST_SUITE_P(Placements, ExactCylinders, ::testing::Range(0, 4),
                         [](const ::testing::TestParamInfo<int>& info) {
                           std::string n = placement(info.param).name;
                           for (char& c : n) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return n;
                         });

}  // namespace
}  // namespace bvh_collision
