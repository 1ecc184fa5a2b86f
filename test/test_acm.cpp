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
    const Srdf srdf = parse_srdf(read_file(dir + "/robot.srdf"));
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
      "<group_state name=\"home\" group=\"arm\"><joint name=\"j1\" value=\"0.5\"/></group_state></robot>");
  AllowedCollisionMatrix acm(m.links().size());
  const auto unknown = apply_srdf(srdf, m, acm);
  EXPECT_EQ(unknown, std::vector<std::string>{"ghost"});
  EXPECT_TRUE(acm.allowed(m.link_index("b"), m.link_index("c")));
  EXPECT_EQ(acm.reason(m.link_index("b"), m.link_index("c")), AcmReason::kSrdfDefault);
  EXPECT_FALSE(acm.allowed(m.link_index("a"), m.link_index("c"))) << "enable_collisions wins";
  EXPECT_DOUBLE_EQ(srdf.group_states.at("home").at("j1"), 0.5);
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
      {"value=\"0x10\"", "'0x10' is not a finite number"}, {"", "value is missing"},
      {"value=\"1e400\"", "'1e400' is not a finite number"}};
  for (const auto& [value, reason] : cases) {
    try {
      parse_srdf("<robot name=\"r\"><group_state name=\"home\" group=\"arm\"><joint name=\"j1\" " + value +
                 "/></group_state></robot>");
      ADD_FAILURE() << value << " parsed";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("<group_state name=\"home\">"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("joint 'j1'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  }
  EXPECT_DOUBLE_EQ(parse_srdf("<robot name=\"r\"><group_state name=\"h\" group=\"a\"><joint name=\"j\" value=\"+1.5e-1\"/>"
                              "</group_state></robot>").group_states.at("h").at("j"), 0.15);
}

}  // namespace
}  // namespace bvh_collision
