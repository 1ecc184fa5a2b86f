// Robot description parsing: the summary of every real robot matches MANIFEST.json (an
// independent count made when the robots were collected), and bad descriptions fail with a
// message that names the problem.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <set>

#include "bvh_collision/robot/package_resolver.h"
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


// ------------------------------------------------------------- malformed robot descriptions

// A four-link robot with a box, a cylinder, a sphere and a mesh; each case below replaces one
// piece of it. The unchanged robot parses.
std::string small_robot(const std::map<std::string, std::string>& changes = {}) {
  std::map<std::string, std::string> v = {
      {"BOX", R"(<box size="0.1 0.2 0.3"/>)"},
      {"CYLINDER", R"(<cylinder radius="0.05" length="0.4"/>)"},
      {"SPHERE", R"(<sphere radius="0.07"/>)"},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="1 1 1"/>)"},
      {"ORIGIN", R"(<origin xyz="0 0 0.1" rpy="0 0 0"/>)"},
      {"J1", R"(<origin xyz="0 0 0.5"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/>)"},
      {"J2_TYPE", "revolute"},
      {"J2_CHILD", "link2"},
      {"J2_AXIS", "1 0 0"},
      {"J3_PARENT", "link2"},
  };
  for (const auto& [k, x] : changes) v[k] = x;
  return "<robot name=\"small\">"
         "<link name=\"base\"><collision>" + v["ORIGIN"] + "<geometry>" + v["BOX"] + "</geometry></collision></link>"
         "<link name=\"link1\"><collision><geometry>" + v["CYLINDER"] + "</geometry></collision></link>"
         "<link name=\"link2\"><collision><geometry>" + v["SPHERE"] + "</geometry></collision></link>"
         "<link name=\"link3\"><collision><geometry>" + v["MESH"] + "</geometry></collision></link>"
         "<joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"link1\"/>" + v["J1"] + "</joint>"
         "<joint name=\"j2\" type=\"" + v["J2_TYPE"] + "\"><parent link=\"link1\"/><child link=\"" + v["J2_CHILD"] + "\"/>"
         "<axis xyz=\"" + v["J2_AXIS"] + "\"/><limit lower=\"0\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>"
         "<joint name=\"j3\" type=\"fixed\"><parent link=\"" + v["J3_PARENT"] + "\"/><child link=\"link3\"/></joint>"
         "</robot>";
}

struct BadCase {
  std::string key, value;
  std::vector<std::string> message;  // every piece must appear in the error
};

TEST(RobotDescription, EveryMalformedCollisionElementIsRefusedByName) {
  ASSERT_NO_THROW(parse_robot_description(small_robot()));
  const std::vector<BadCase> cases = {
      {"CYLINDER", R"(<cylinder radius="nan" length="0.4"/>)", {"link 'link1', collision element 1", "'radius'", "'nan'", "not finite"}},
      {"CYLINDER", R"(<cylinder radius="inf" length="0.4"/>)", {"link 'link1'", "'inf'", "not finite"}},
      {"CYLINDER", R"(<cylinder radius="abc" length="0.4"/>)", {"link 'link1'", "'abc'", "not a number"}},
      {"CYLINDER", R"(<cylinder radius="" length="0.4"/>)", {"link 'link1'", "'radius'", "needs 1 number, got 0"}},
      {"CYLINDER", R"(<cylinder radius="0.05" length="nan"/>)", {"'length'", "not finite"}},
      {"CYLINDER", R"(<cylinder radius="0.05"/>)", {"'length'", "missing"}},
      // strtod reads hexadecimal, urdfdom does not (and dropped the element): not a number here.
      {"CYLINDER", R"(<cylinder radius="0x10" length="0.4"/>)", {"link 'link1'", "'0x10'", "not a number"}},
      {"SPHERE", R"(<sphere radius="0X1p-3"/>)", {"link 'link2'", "not a number"}},
      {"CYLINDER", R"(<cylinder radius="+-1" length="0.4"/>)", {"link 'link1'", "not a number"}},
      {"SPHERE", R"(<sphere radius="1e-99999"/>)", {"link 'link2'", "positive"}},
      {"CYLINDER", R"(<cylinder radius="1e300" length="0.4"/>)", {"'1e300'", "beyond"}},
      {"CYLINDER", R"(<cylinder radius="0.05" length="-1"/>)", {"'length'", "positive"}},
      {"SPHERE", R"(<sphere radius="nan"/>)", {"link 'link2', collision element 1", "not finite"}},
      {"SPHERE", R"(<sphere radius="inf"/>)", {"link 'link2'", "not finite"}},
      {"BOX", R"(<box size="nan 1 1"/>)", {"link 'base'", "'size'", "not finite"}},
      {"BOX", R"(<box size="inf 1 1"/>)", {"link 'base'", "not finite"}},
      {"BOX", R"(<box size="a b c"/>)", {"link 'base'", "not a number"}},
      {"BOX", R"(<box size="1 1"/>)", {"link 'base'", "needs 3 numbers, got 2"}},
      {"BOX", R"(<box size="1 1 1 1"/>)", {"link 'base'", "needs 3 numbers, got 4"}},
      {"BOX", R"(<box size="1e308 1 1"/>)", {"link 'base'", "beyond"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="nan 1 1"/>)", {"link 'link3'", "'scale'", "not finite"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="inf 1 1"/>)", {"link 'link3'", "not finite"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="x y z"/>)", {"link 'link3'", "not a number"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="1"/>)", {"link 'link3'", "needs 3 numbers, got 1"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="1 1"/>)", {"needs 3 numbers, got 2"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="1e300 1 1"/>)", {"beyond"}},
      {"MESH", R"(<mesh filename="package://p/m.stl" scale="0 1 1"/>)", {"must not be zero"}},
      {"MESH", R"(<mesh/>)", {"link 'link3'", "no filename"}},
      {"MESH", R"(<capsule radius="0.1" length="0.2"/>)", {"link 'link3'", "unknown shape <capsule>", "box, sphere, cylinder, mesh"}},
      {"MESH", "", {"link 'link3'", "<geometry> is empty"}},
      {"ORIGIN", R"(<origin xyz="nan 0 0"/>)", {"link 'base', collision element 1", "'xyz'", "not finite"}},
      {"ORIGIN", R"(<origin xyz="a b c"/>)", {"link 'base'", "not a number"}},
      {"ORIGIN", R"(<origin xyz="0 0"/>)", {"link 'base'", "needs 3 numbers, got 2"}},
      {"ORIGIN", R"(<origin rpy="0 inf 0"/>)", {"'rpy'", "not finite"}},
      {"ORIGIN", R"(<origin xyz="0 0 e99999999999999999999"/>)", {"not"}},
  };
  for (const BadCase& c : cases) {
    const std::string msg = parse_error(small_robot({{c.key, c.value}}));
    for (const std::string& piece : c.message) {
      EXPECT_NE(msg.find(piece), std::string::npos) << c.key << " = " << c.value << ": " << msg;
    }
  }
}

TEST(RobotDescription, JointErrorsAreRefusedByName) {
  const std::vector<BadCase> cases = {
      {"J1", R"(<origin xyz="1e308 0 0"/><axis xyz="0 0 1"/>)", {"joint 'j1'", "'1e308 0 0'", "beyond"}},
      {"J1", R"(<origin xyz="nan 0 0"/><axis xyz="0 0 1"/>)", {"joint 'j1'", "not finite"}},
      {"J1", R"(<axis xyz="0 0 0"/>)", {"joint 'j1'", "zero axis"}},
      {"J1", R"(<axis xyz="0 0 nan"/>)", {"joint 'j1'", "not finite"}},
      {"J1", R"(<axis xyz="0 0 1"/><limit lower="1" upper="-1" effort="1" velocity="1"/>)", {"joint 'j1'", "lower '1' is above upper '-1'"}},
      {"J1", R"(<axis xyz="0 0 1"/><limit lower="nan" upper="1" effort="1" velocity="1"/>)", {"joint 'j1'", "not finite"}},
      {"J2_CHILD", "link1", {"joint 'j2'", "parent link 'link1' is also its child"}},
      {"J3_PARENT", "base\"/><child link=\"link2", {"link 'link2'", "child of two joints", "'j2'", "'j3'"}},
  };
  for (const BadCase& c : cases) {
    const std::string msg = parse_error(small_robot({{c.key, c.value}}));
    for (const std::string& piece : c.message) {
      EXPECT_NE(msg.find(piece), std::string::npos) << c.key << " = " << c.value << ": " << msg;
    }
  }
  // A fixed joint's axis is not read (urdfdom ignores it): zero there is no error.
  EXPECT_NO_THROW(parse_robot_description(small_robot({{"J2_TYPE", "fixed"}, {"J2_AXIS", "0 0 0"}})));
}

// urdfdom reads XML with TinyXML 1, which read the unknown entity in "b&ase" as "base" where the
// validation (tinyxml2) read "b&ase": two documents. urdfdom now reads the validated one (found
// by fuzz_robot_description).
TEST(RobotDescription, UrdfdomReadsTheDocumentThatWasValidated) {
  const std::string xml =
      "<robot name=\"r\"><link name=\"b&ase\"><collision><geometry><box size=\"1 1 1\"/></geometry></collision></link>"
      "<link name=\"l\"/><joint name=\"j\" type=\"fixed\"><parent link=\"b&amp;ase\"/><child link=\"l\"/></joint></robot>";
  const auto model = parse_robot_description(xml);
  ASSERT_TRUE(model->getLink("b&ase")) << "the link keeps the name that was validated";
  EXPECT_EQ(model->getLink("b&ase")->collision_array.size(), 1u);
  EXPECT_FALSE(model->getLink("base"));
}

// Numbers split by tabs and line breaks (found by fuzz_robot_description): the validation read
// three numbers, urdfdom (which splits on spaces) failed the origin and dropped the whole
// <collision> without a word. XML's attribute normalization makes them spaces for both.
TEST(RobotDescription, LineBreaksBetweenNumbersKeepTheElement) {
  const std::string xml =
      "<robot name=\"r\"><link name=\"b\"><collision><origin xyz=\"0\n\n 0\t0.1\" rpy=\"0\r\n0 0\"/>"
      "<geometry><box size=\"0.1\n0.2 0.3\"/></geometry></collision></link></robot>";
  const auto model = parse_robot_description(xml);
  ASSERT_EQ(model->getLink("b")->collision_array.size(), 1u);
  const auto& collision = *model->getLink("b")->collision_array[0];
  EXPECT_DOUBLE_EQ(collision.origin.position.z, 0.1);
  const auto* box = dynamic_cast<const urdf::Box*>(collision.geometry.get());
  ASSERT_NE(box, nullptr);
  EXPECT_DOUBLE_EQ(box->dim.y, 0.2);
}

TEST(RobotDescription, OnlyRegularFilesAreRead) {
  for (const std::string path : {"/dev/zero", "/tmp", "/dev/null"}) {
    try {
      load_robot_description_file(path);
      FAIL() << path << " was read";
    } catch (const RobotDescriptionError& e) {
      EXPECT_NE(std::string(e.what()).find("is not a regular file"), std::string::npos) << e.what();
    }
  }
}

// A mesh file name holding a control character: "&#0;" became a NUL that ended the C string, so
// "mesh.stl&#0;x" loaded mesh.stl. Refused before any file is opened, naming link and element;
// the resolver refuses such a URI too (the service path: a ROS string may hold a NUL).
TEST(RobotDescription, ControlCharactersInMeshFileNamesAreRefused) {
  for (const std::string name : {"mesh.stl&#0;x", "mesh.stl&#x00;", "me&#10;sh.stl", "mesh.stl&#X1f;", "mesh.stl&#127;",
                                  "mesh\x02.stl"}) {
    try {
      parse_robot_description("<robot name='r'><link name='arm'><collision><geometry><mesh filename='file:///tmp/" + name +
                              "'/></geometry></collision></link></robot>");
      ADD_FAILURE() << name << " parsed";
    } catch (const RobotDescriptionError& e) {
      EXPECT_NE(std::string(e.what()).find("link 'arm', collision element 1: <mesh> attribute 'filename' holds a control character"),
                std::string::npos) << e.what();
    }
  }
  // Character references to other characters are names like any other.
  const auto model = parse_robot_description(
      "<robot name='r'><link name='arm'><collision><geometry><mesh filename='file:///tmp/m&#233;sh&#32;&amp;.stl'/>"
      "</geometry></collision></link></robot>");
  const auto* mesh = dynamic_cast<const urdf::Mesh*>(model->getLink("arm")->collision->geometry.get());
  ASSERT_NE(mesh, nullptr);
  EXPECT_EQ(mesh->filename, "file:///tmp/m\xc3\xa9sh &.stl");
  const PackageResolver resolver({});
  EXPECT_EQ(resolver.resolve("file:///tmp/box.stl"), "/tmp/box.stl");
  try {
    resolver.resolve(std::string("file:///tmp/box.stl\0x", 21));
    ADD_FAILURE() << "a URI with a NUL resolved";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("holds a control character (U+0000 at byte 19)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace bvh_collision
