// The allowed-collision matrix: adjacency with geometry-less links collapsed, and SRDF entries.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "bvh_collision/robot/allowed_collision_matrix.h"
#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

RobotModel model_from(const std::string& xml) {
  return RobotModel::from_urdf(*parse_robot_description(xml), PackageResolver({}));
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::set<std::pair<std::string, std::string>> allowed_pairs(const RobotModel& m, const AllowedCollisionMatrix& acm) {
  std::set<std::pair<std::string, std::string>> out;
  for (std::size_t a = 0; a < m.links().size(); ++a) {
    for (std::size_t b = a + 1; b < m.links().size(); ++b) {
      if (acm.allowed(a, b)) out.insert(std::minmax(m.links()[a].name, m.links()[b].name));
    }
  }
  return out;
}

TEST(AllowedCollisionMatrix, DemoRobotAdjacency) {
  const RobotModel m = RobotModel::from_urdf(*load_robot_description_file(test::source_dir() + "/urdf/demo_arm.urdf"),
                                             PackageResolver({}));
  const auto allowed = allowed_pairs(m, AllowedCollisionMatrix::adjacent_links(m));
  const std::set<std::pair<std::string, std::string>> expected = {
      {"base_link", "link1"}, {"link1", "link2"}, {"link2", "link3"},         {"link3", "link4"},
      {"link4", "link5"},     {"link5", "link6"}, {"hand", "link6"},          {"finger_left", "hand"},
      {"finger_right", "hand"}};
  EXPECT_EQ(allowed, expected);
}

TEST(AllowedCollisionMatrix, LinksWithoutGeometryAreCollapsed) {
  const std::string box = "<collision><geometry><box size=\"1 1 1\"/></geometry></collision>";
  const RobotModel m = model_from(
      "<robot name=\"r\"><link name=\"a\">" + box + "</link><link name=\"mount\"/>"
      "<link name=\"b\">" + box + "</link><link name=\"c\">" + box + "</link><link name=\"d\">" + box + "</link>"
      "<joint name=\"j1\" type=\"fixed\"><parent link=\"a\"/><child link=\"mount\"/></joint>"
      "<joint name=\"j2\" type=\"fixed\"><parent link=\"mount\"/><child link=\"b\"/></joint>"
      "<joint name=\"j3\" type=\"fixed\"><parent link=\"mount\"/><child link=\"c\"/></joint>"
      "<joint name=\"j4\" type=\"fixed\"><parent link=\"c\"/><child link=\"d\"/></joint></robot>");
  const auto allowed = allowed_pairs(m, AllowedCollisionMatrix::adjacent_links(m));
  const std::set<std::pair<std::string, std::string>> expected = {{"a", "b"}, {"a", "c"}, {"b", "c"}, {"c", "d"}};
  EXPECT_EQ(allowed, expected);
}

TEST(AllowedCollisionMatrix, RealSrdfs) {
  BVH_REQUIRE_ROBOTS();
  for (const auto& [robot, disabled] : std::map<std::string, std::size_t>{{"panda", 0}, {"pr2", 1081}, {"ur5e", 0}}) {
    SCOPED_TRACE(robot);
    const std::string dir = test::robots_dir() + "/" + robot;
    const RobotModel m = RobotModel::from_urdf(*load_robot_description_file(dir + "/robot.urdf"), PackageResolver({dir}));
    const Srdf srdf = parse_srdf(read_file(dir + "/robot.srdf"), &m);
    if (disabled > 0) {
      EXPECT_EQ(srdf.disabled_pairs.size(), disabled);
    }
    AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(m);
    const auto unknown = apply_srdf(srdf, m, acm);
    for (const auto& [l1, l2] : srdf.disabled_pairs) {
      const int a = m.link_index(l1), b = m.link_index(l2);
      if (a >= 0 && b >= 0) {
        EXPECT_TRUE(acm.allowed(a, b)) << l1 << " " << l2;
      } else {
        EXPECT_TRUE(std::count(unknown.begin(), unknown.end(), a < 0 ? l1 : l2)) << "unknown name reported";
      }
    }
  }
}

TEST(AllowedCollisionMatrix, EnableWinsOverDisable) {
  const std::string box = "<collision><geometry><box size=\"1 1 1\"/></geometry></collision>";
  const RobotModel m = model_from("<robot name=\"r\"><link name=\"a\">" + box + "</link><link name=\"b\">" + box +
                                  "</link><link name=\"c\">" + box + "</link>"
                                  "<joint name=\"j1\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint>"
                                  "<joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint></robot>");
  const Srdf srdf = parse_srdf(
      "<robot name=\"r\"><disable_default_collisions link=\"c\"/><enable_collisions link1=\"a\" link2=\"c\"/>"
      "<disable_collisions link1=\"a\" link2=\"ghost\" reason=\"Never\"/>"
      "<group name=\"arm\"><joint name=\"j1\"/></group>"
      "<group_state name=\"home\" group=\"arm\"><joint name=\"j1\" value=\"0.5\"/></group_state></robot>");
  AllowedCollisionMatrix acm(m.links().size());
  const auto unknown = apply_srdf(srdf, m, acm);
  EXPECT_EQ(unknown, std::vector<std::string>{"ghost"});
  EXPECT_TRUE(acm.allowed(m.link_index("b"), m.link_index("c")));
  EXPECT_EQ(acm.reason(m.link_index("b"), m.link_index("c")), AcmReason::kSrdfDefault);
  EXPECT_FALSE(acm.allowed(m.link_index("a"), m.link_index("c"))) << "enable_collisions wins";
  EXPECT_EQ(srdf.group_states.at("home").at("j1").values, std::vector<double>{0.5});
}

TEST(AllowedCollisionMatrix, MalformedSrdfIsAnError) {
  try {
    parse_srdf("<robot name=\"r\"><disable_collisions link1=\"a\"></robot>");
    FAIL() << "parsed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("line 1"), std::string::npos) << e.what();
  }
}

// tinyxml2's DoubleAttribute read a group state's "abc", "0x10" or missing value as 0 (or 16).
TEST(AllowedCollisionMatrix, GroupStateValuesAreFiniteNumbers) {
  const std::pair<std::string, std::string> cases[] = {
      {"value=\"abc\"", "'abc' is not a finite number"}, {"value=\"nan\"", "'nan' is not a finite number"},
      {"value=\"0x10\"", "'0x10' is not a finite number"},
      {"value=\"1e400\"", "'1e400' is not a finite number"}};
  for (const auto& [value, reason] : cases) {
    try {
      parse_srdf("<robot name=\"r\"><group name=\"arm\"/><group_state name=\"home\" group=\"arm\"><joint name=\"j1\" " + value +
                 "/></group_state></robot>");
      ADD_FAILURE() << value << " parsed";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("<group_state name=\"home\">"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("joint 'j1'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  }
  EXPECT_DOUBLE_EQ(parse_srdf("<robot name=\"r\"><group name=\"a\"/><group_state name=\"h\" group=\"a\"><joint name=\"j\" value=\"+1.5e-1\"/>"
                              "</group_state></robot>").group_states.at("h").at("j").values.at(0), 0.15);
}

// A humanoid with a floating base, as MoveIt loads it: the base is a <virtual_joint> of the SRDF
// and a <group_state> gives it all seven values in one attribute (x y z qx qy qz qw), written
// with trailing points as the public description does. srdfdom reads a list; it was refused as
// "not a finite number".
const char* const kHumanoidUrdf =
    "<robot name=\"humanoid\">"
    "<link name=\"base_link\"><collision><geometry><box size=\"0.3 0.2 0.2\"/></geometry></collision></link>"
    "<link name=\"leg\"><collision><geometry><cylinder radius=\"0.05\" length=\"0.6\"/></geometry></collision></link>"
    "<joint name=\"hip\" type=\"revolute\"><parent link=\"base_link\"/><child link=\"leg\"/>"
    "<origin xyz=\"0 0 -0.4\"/><axis xyz=\"0 1 0\"/><limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
    "</robot>";

std::string humanoid_srdf(const std::string& root_value) {
  return "<robot name=\"humanoid\">\n"
         "<virtual_joint name=\"root_joint\" type=\"floating\" parent_frame=\"world\" child_link=\"base_link\"/>\n"
         "<group name=\"all\"><joint name=\"root_joint\"/><joint name=\"hip\"/></group>\n"
         "<group_state name=\"half_sitting\" group=\"all\">\n"
         "<joint name=\"root_joint\" value=\"" + root_value + "\" />\n"
         "<joint name=\"hip\" value=\"-0.4\" />\n"
         "</group_state>\n</robot>";
}

TEST(AllowedCollisionMatrix, FloatingBaseGroupStateIsAList) {
  const RobotModel m = model_from(kHumanoidUrdf);
  const Srdf srdf = parse_srdf(humanoid_srdf("0. 0. 1.01927 0. 0. 0. 1."), &m);
  ASSERT_EQ(srdf.virtual_joints.size(), 1u);
  EXPECT_EQ(srdf.virtual_joints[0].type, JointType::kFloating);
  EXPECT_EQ(srdf.virtual_joints[0].child_link, "base_link");
  const auto& state = srdf.group_states.at("half_sitting");
  EXPECT_EQ(state.at("root_joint").values, (std::vector<double>{0, 0, 1.01927, 0, 0, 0, 1}));
  EXPECT_EQ(state.at("hip").values, std::vector<double>{-0.4});
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(m);
  EXPECT_TRUE(apply_srdf(srdf, m, acm).empty());
  // Without the model the virtual joint is still known: its count is checked all the same.
  EXPECT_EQ(parse_srdf(humanoid_srdf("1 2 3 0 0 0 1")).group_states.at("half_sitting").at("root_joint").values.size(), 7u);
}

TEST(AllowedCollisionMatrix, FloatingBaseQuaternionIsNormalisedOrIgnored) {
  const RobotModel m = model_from(kHumanoidUrdf);
  // A quaternion of length 2 (and one of tiny length, whose squares underflow) becomes unit.
  for (const std::string value : {"1 2 3 0 0 0 2", "1 2 3 0 0 0 1e-200", "1 2 3 0 0 3e200 4e200"}) {
    const std::vector<double> v = parse_srdf(humanoid_srdf(value), &m).group_states.at("half_sitting").at("root_joint").values;
    ASSERT_EQ(v.size(), 7u) << value;
    EXPECT_EQ(v[0], 1.0);
    EXPECT_EQ(v[2], 3.0);
    EXPECT_NEAR(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6], 1.0, 1e-15) << value;
  }
  // A zero one is no rotation: MoveIt loads the robot, so do we; the state leaves the joint alone.
  const Srdf zero = parse_srdf(humanoid_srdf("0 0 1 0 0 0 0"), &m);
  EXPECT_EQ(zero.group_states.at("half_sitting").count("root_joint"), 0u);
  EXPECT_EQ(zero.group_states.at("half_sitting").count("hip"), 1u);
  ASSERT_EQ(zero.warnings.size(), 1u);
  EXPECT_NE(zero.warnings[0].find("joint 'root_joint' (floating) has a zero quaternion"), std::string::npos) << zero.warnings[0];
  EXPECT_NE(zero.warnings[0].find("<group_state name=\"half_sitting\"> (line 5)"), std::string::npos) << zero.warnings[0];
}

// A planar joint in the URDF (x y theta), and one as the SRDF's virtual joint of a mobile base.
TEST(AllowedCollisionMatrix, PlanarGroupStatesTakeThreeValues) {
  const RobotModel m = model_from(
      "<robot name=\"rover\"><link name=\"floor\"/>"
      "<link name=\"body\"><collision><geometry><box size=\"0.5 0.4 0.2\"/></geometry></collision></link>"
      "<joint name=\"drive\" type=\"planar\"><parent link=\"floor\"/><child link=\"body\"/><axis xyz=\"0 0 1\"/></joint></robot>");
  const Srdf srdf = parse_srdf(
      "<robot name=\"rover\"><virtual_joint name=\"odom\" type=\"planar\" parent_frame=\"map\" child_link=\"floor\"/>"
      "<group name=\"base\"/><group_state name=\"parked\" group=\"base\"><joint name=\"drive\" value=\"0.5 -0.25 1.\"/>"
      "<joint name=\"odom\" value=\"10 20 -3.\"/></group_state></robot>", &m);
  EXPECT_EQ(srdf.group_states.at("parked").at("drive").values, (std::vector<double>{0.5, -0.25, 1.0}));
  EXPECT_EQ(srdf.group_states.at("parked").at("odom").values, (std::vector<double>{10, 20, -3}));
  EXPECT_EQ(group_state_value_count(JointType::kPlanar), 3u);
  EXPECT_EQ(group_state_value_count(JointType::kFloating), 7u);
  EXPECT_EQ(group_state_value_count(JointType::kFixed), 0u);
  EXPECT_EQ(group_state_value_count(JointType::kContinuous), 1u);
}

// What srdfdom and MoveIt's RobotModel log and skip, we skip with a warning that names it; the
// robot loads (the public benchmark's panda SRDF gives its fixed finger joint a value in the
// state "close": MoveIt loads the robot, we stopped with "needs 0 values, got 1"). A value that is
// not a number stays an error.
TEST(AllowedCollisionMatrix, WhatMoveItSkipsIsAWarningAndSkipped) {
  const RobotModel m = model_from(kHumanoidUrdf);
  const std::string group = "<group name=\"g\"/>";
  const std::pair<std::string, std::string> cases[] = {
      {humanoid_srdf("0 0 1 0 0 1"), "joint 'root_joint' (floating) needs 7 values (x y z qx qy qz qw), got 6: this state does not set it"},
      {humanoid_srdf("0 0 1 0 0 0 1 0"), "joint 'root_joint' (floating) needs 7 values (x y z qx qy qz qw), got 8"},
      {"<robot name=\"humanoid\">" + group + "<group_state name=\"s\" group=\"g\"><joint name=\"hip\" value=\"0.1 0.2\"/></group_state></robot>",
       "joint 'hip' (revolute) needs 1 value, got 2"},
      {"<robot name=\"humanoid\"><virtual_joint name=\"v\" type=\"planar\" parent_frame=\"w\" child_link=\"base_link\"/>" + group +
       "<group_state name=\"s\" group=\"g\"><joint name=\"v\" value=\"1 2\"/></group_state></robot>",
       "joint 'v' (planar) needs 3 values (x y theta), got 2"},
      {"<robot name=\"humanoid\"><virtual_joint name=\"v\" type=\"fixed\" parent_frame=\"w\" child_link=\"base_link\"/>" + group +
       "<group_state name=\"s\" group=\"g\"><joint name=\"v\" value=\"1\"/></group_state></robot>",
       "joint 'v' (fixed) needs 0 values, got 1"},
      {"<robot name=\"humanoid\"><virtual_joint name=\"v\" type=\"hinge\" parent_frame=\"w\" child_link=\"base_link\"/></robot>",
       "<virtual_joint> (line 1): 'v' of type 'hinge': taken as fixed"},
      {"<robot name=\"humanoid\"><virtual_joint name=\"v\" type=\"fixed\" parent_frame=\"w\" child_link=\"nowhere\"/></robot>",
       "holds link 'nowhere', which the robot does not have: ignored"},
      {"<robot name=\"humanoid\"><group_state name=\"s\" group=\"nogroup\"><joint name=\"hip\" value=\"1\"/></group_state></robot>",
       "'s' is of group 'nogroup', which the SRDF does not define: ignored"},
      {"<robot name=\"humanoid\">" + group + "<group_state name=\"s\" group=\"g\"><joint name=\"knee\" value=\"1\"/></group_state></robot>",
       "joint 'knee' is not a joint of the robot: ignored"},
      {"<robot name=\"humanoid\">" + group + "<group_state name=\"s\" group=\"g\"><joint name=\"hip\"/></group_state></robot>",
       "a joint without a name or a value: ignored"},
      {"<robot name=\"humanoid\"><disable_collisions link1=\"base_link\"/></robot>", "<disable_collisions> (line 1): link1 or link2 is missing"},
      {"<robot name=\"other\"/>", "SRDF is for robot 'other', the URDF is 'humanoid'"}};
  for (const auto& [xml, reason] : cases) {
    const Srdf srdf = parse_srdf(xml, &m);
    ASSERT_EQ(srdf.warnings.size(), 1u) << xml;
    EXPECT_NE(srdf.warnings[0].find(reason), std::string::npos) << srdf.warnings[0];
    for (const auto& [state, joints] : srdf.group_states) {
      EXPECT_TRUE(joints.empty() || state == "half_sitting") << xml;
    }
  }
  // The virtual joint of an unknown type is kept, as fixed; names are trimmed as srdfdom trims them.
  const Srdf hinge = parse_srdf("<robot name=\"humanoid\"><virtual_joint name=\" v \" type=\" Planar \" parent_frame=\"w\" child_link=\" base_link\"/>"
                                "<disable_collisions link1=\" base_link \" link2=\"leg \"/></robot>", &m);
  ASSERT_EQ(hinge.virtual_joints.size(), 1u);
  EXPECT_EQ(hinge.virtual_joints[0].name, "v");
  EXPECT_EQ(hinge.virtual_joints[0].type, JointType::kPlanar);
  ASSERT_EQ(hinge.disabled_pairs.size(), 1u);
  EXPECT_EQ(hinge.disabled_pairs[0], std::make_pair(std::string("base_link"), std::string("leg")));
  EXPECT_TRUE(hinge.warnings.empty());
  // Still refused: what srdfdom refuses (not XML, no <robot>) and a value that is not a number.
  for (const auto& [xml, reason] : std::vector<std::pair<std::string, std::string>>{
           {humanoid_srdf("0 0 1 0 0 0 1.x"), "'1.x' is not a finite number"},
           {humanoid_srdf("   "), "holds no number"},
           {"<robot name=\"h\"><unclosed></robot>", "SRDF is not well-formed XML"},
           {"<robots/>", "SRDF has no <robot> root element"}}) {
    try {
      parse_srdf(xml, &m);
      ADD_FAILURE() << xml << " parsed";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace bvh_collision
