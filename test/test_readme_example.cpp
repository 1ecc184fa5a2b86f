// The README's C++ example, compiled and run: the lines between the markers are the README's
// ```cpp block, character for character (readme_examples.test compares them), so the guide's
// first query cannot rot.
#include <gtest/gtest.h>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/robot/package_resolver.h"
#include "bvh_collision/robot/robot_description.h"
#include "checker_fixtures.h"

TEST(Readme, FirstQueryInCpp) {
  const std::string urdf_path = bvh_collision::test::source_dir() + "/urdf/demo_arm.urdf";
  bool hits = false, self = true;
  {
    // README begin
using namespace bvh_collision;  // urdf_path: the robot's URDF, e.g. "urdf/demo_arm.urdf"
RobotModel model = RobotModel::from_urdf(*load_robot_description_file(urdf_path), PackageResolver({}));
AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
CollisionChecker checker(std::move(model), std::move(acm));
Environment world(0.02);  // a 2 cm octree (clouds go in with insert_scan) and collision objects
world.add_object("pillar", ObjectShape::box({0.12, 0.12, 0.8}), Transform::Translation({0.45, 0.35, 0.4}));
std::vector<double> q(checker.model().variable_count(), 0.0);  // in model().variable_names() order
q[0] = 0.66, q[1] = 1.0;                                          // joint1, joint2
hits = checker.check_environment(q.data(), world).collision;      // true: the arm is in the pillar
self = checker.check_self(q.data()).collision;                    // false
    // README end
    ASSERT_EQ(checker.model().variable_names()[0], "joint1");
    ASSERT_EQ(checker.model().variable_names()[1], "joint2");
  }
  EXPECT_TRUE(hits);
  EXPECT_FALSE(self);
}
