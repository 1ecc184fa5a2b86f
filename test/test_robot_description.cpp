// Robot description parsing: the summary of every real robot matches MANIFEST.json (an
// independent count made when the robots were collected), and bad descriptions fail with a
// message that names the problem.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

using nlohmann::json;

json read_manifest() {
  std::ifstream in(test::robots_dir() + "/MANIFEST.json");
  return json::parse(in);
}

std::map<std::string, std::size_t> as_count_map(const json& j) {
  std::map<std::string, std::size_t> m;
  for (const auto& [k, v] : j.items()) m[k] = v.get<std::size_t>();
  return m;
}

// The manifest writes a link with several collision elements as "name(3: cylinder+sphere+sphere)".
std::set<std::string> multi_collision_strings(const RobotSummary& s) {
  std::set<std::string> out;
  for (const auto& [link, types] : s.links_with_multiple_collisions) {
    std::string text = link + "(" + std::to_string(types.size()) + ": ";
    for (std::size_t i = 0; i < types.size(); ++i) text += (i ? "+" : "") + types[i];
    out.insert(text + ")");
  }
  return out;
}

TEST(RobotDescription, SummaryOfEveryRealRobotMatchesManifest) {
  BVH_REQUIRE_ROBOTS();
  const json manifest = read_manifest();
  ASSERT_GE(manifest.size(), 6u) << "MANIFEST.json lists fewer robots than the README";
  for (const auto& [robot, expected] : manifest.items()) {
    SCOPED_TRACE(robot);
    const auto model = load_robot_description_file(test::robots_dir() + "/" + robot + "/robot.urdf");
    const RobotSummary s = summarize(*model);
    EXPECT_EQ(s.name, expected["robot_name"].get<std::string>());
    EXPECT_EQ(s.links, expected["links"].get<std::size_t>());
    EXPECT_EQ(s.joints, expected["joints"].get<std::size_t>());
    EXPECT_EQ(s.joint_types, as_count_map(expected["joint_types"]));
    EXPECT_EQ(s.mimic_joints, expected["mimic_joints"].get<std::size_t>());
    EXPECT_EQ(s.collision_elements, expected["collision_elements"].get<std::size_t>());
    EXPECT_EQ(s.collision_geometry, as_count_map(expected["collision_geom"]));
    EXPECT_EQ(s.links_without_collision, expected["links_without_collision"].get<std::size_t>());
    EXPECT_EQ(s.nonidentity_collision_origins,
              expected["nonidentity_collision_origins"].get<std::size_t>());
    const auto listed = expected["links_with_multiple_collisions"].get<std::set<std::string>>();
    EXPECT_EQ(multi_collision_strings(s), listed);
  }
}

TEST(RobotDescription, DemoRobotSummary) {
  const auto model = load_robot_description_file(test::source_dir() + "/urdf/demo_arm.urdf");
  const RobotSummary s = summarize(*model);
  EXPECT_EQ(s.name, "demo_arm");
  EXPECT_EQ(s.root_link, "base_link");
  EXPECT_EQ(s.links, 11u);
  EXPECT_EQ(s.joints, 10u);
  EXPECT_EQ(s.mimic_joints, 1u);
  EXPECT_EQ(s.collision_elements, 11u);
  EXPECT_EQ(s.links_without_collision, 1u);  // tool_frame
  const std::map<std::string, std::size_t> geometry{{"box", 4}, {"cylinder", 5}, {"sphere", 2}};
  EXPECT_EQ(s.collision_geometry, geometry);
  ASSERT_EQ(s.links_with_multiple_collisions.count("link2"), 1u);
  EXPECT_EQ(s.links_with_multiple_collisions.at("link2"),
            (std::vector<std::string>{"cylinder", "sphere"}));
  // The one-line summary a user sees names the robot and every count.
  const std::string line = s.to_string();
  EXPECT_NE(line.find("robot 'demo_arm'"), std::string::npos) << line;
  EXPECT_NE(line.find("11 links"), std::string::npos) << line;
  EXPECT_NE(line.find("10 joints"), std::string::npos) << line;
  EXPECT_NE(line.find("11 collision elements"), std::string::npos) << line;
}

// Parses `xml` expecting failure; returns the message.
std::string parse_error(const std::string& xml) {
  try {
    parse_robot_description(xml);
  } catch (const RobotDescriptionError& e) {
    return e.what();
  }
  ADD_FAILURE() << "parse succeeded on a bad description: " << xml;
  return "";
}

TEST(RobotDescription, EmptyDescriptionIsNamed) {
  EXPECT_NE(parse_error("").find("empty"), std::string::npos);
  EXPECT_NE(parse_error("  \n\t ").find("empty"), std::string::npos);
}

TEST(RobotDescription, MalformedXmlGivesTheLine) {
  const std::string msg = parse_error("<robot name=\"r\">\n<link name=\"a\">\n</robot>");
  EXPECT_NE(msg.find("not well-formed XML"), std::string::npos) << msg;
  EXPECT_NE(msg.find("(line 2)"), std::string::npos) << msg;  // where <link> opens
}

TEST(RobotDescription, WrongRootElementIsNamed) {
  const std::string msg = parse_error("<sdf version=\"1.6\"><model name=\"m\"/></sdf>");
  EXPECT_NE(msg.find("<robot>"), std::string::npos) << msg;
  EXPECT_NE(msg.find("<sdf>"), std::string::npos) << msg;
}

TEST(RobotDescription, UrdfdomRejectionCarriesItsReason) {
  // A joint whose child link does not exist: well-formed XML that urdfdom refuses.
  const std::string msg = parse_error(
      "<robot name=\"r\"><link name=\"a\"/>"
      "<joint name=\"j\" type=\"fixed\"><parent link=\"a\"/><child link=\"ghost\"/></joint></robot>");
  EXPECT_NE(msg.find("urdfdom rejected"), std::string::npos) << msg;
  EXPECT_NE(msg.find("ghost"), std::string::npos) << msg;
}

TEST(RobotDescription, MissingFileIsNamed) {
  try {
    load_robot_description_file("/nonexistent/robot.urdf");
    FAIL() << "loading a missing file succeeded";
  } catch (const RobotDescriptionError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/robot.urdf"), std::string::npos) << e.what();
  }
}

TEST(RobotDescription, JointTypeNames) {
  EXPECT_STREQ(joint_type_name(urdf::Joint::REVOLUTE), "revolute");
  EXPECT_STREQ(joint_type_name(urdf::Joint::CONTINUOUS), "continuous");
  EXPECT_STREQ(joint_type_name(urdf::Joint::PRISMATIC), "prismatic");
  EXPECT_STREQ(joint_type_name(urdf::Joint::FIXED), "fixed");
  EXPECT_STREQ(joint_type_name(urdf::Joint::FLOATING), "floating");
  EXPECT_STREQ(joint_type_name(urdf::Joint::PLANAR), "planar");
}

}  // namespace
}  // namespace bvh_collision
