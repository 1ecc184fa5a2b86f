// The bvh_collision_check tool: output format, ACM printing and errors, on the demo robot.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "check_tool.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

namespace fs = std::filesystem;

struct ToolRun {
  int code;
  std::string out, err;
};

ToolRun run(const std::vector<std::string>& args) {
  std::ostringstream out, err;
  const int code = run_check_tool(args, out, err);
  return {code, out.str(), err.str()};
}

std::string write_states(const std::string& text) {
  static int counter = 0;
  const fs::path path = fs::temp_directory_path() /
                        ("bvh_states_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".txt");
  std::ofstream(path) << text;
  return path.string();
}

const std::string kUrdf = test::source_dir() + "/urdf/demo_arm.urdf";

// The lines of a run that succeeded.
std::vector<std::string> output_lines(const ToolRun& r) {
  EXPECT_EQ(r.code, 0) << r.err;
  std::vector<std::string> lines;
  std::istringstream in(r.out);
  for (std::string l; std::getline(in, l);) lines.push_back(l);
  return lines;
}

TEST(CheckTool, FreeAndFoldedConfigurations) {
  const std::string states = write_states(
      "joints: joint2 joint3\n# comment line\n\n0 0\n1.2 2.6\n");
  const std::vector<std::string> lines = output_lines(run({"--urdf", kUrdf, "--states", states, "--distance"}));
  ASSERT_EQ(lines.size(), 2u);
  const std::string& first = lines[0];
  const std::string& second = lines[1];
  EXPECT_EQ(first.rfind("0 free distance=", 0), 0u) << first;
  EXPECT_NE(first.find(" pair="), std::string::npos) << first;
  EXPECT_EQ(second.rfind("1 collision ", 0), 0u) << second;
  EXPECT_NE(second.find("distance=0 "), std::string::npos) << second;
  // Pairs are name-sorted within a pair, and the list is sorted and comma-separated.
  const std::string pairs = second.substr(12, second.find(" distance=") - 12);
  std::vector<std::string> split;
  std::istringstream ps(pairs);
  for (std::string p; std::getline(ps, p, ',');) {
    const auto colon = p.find(':');
    EXPECT_LT(p.substr(0, colon), p.substr(colon + 1)) << p;
    split.push_back(p);
  }
  EXPECT_FALSE(split.empty());
  EXPECT_TRUE(std::is_sorted(split.begin(), split.end()));
}

// --scene: the demo arm against a MoveIt .scene of the demo's pillar (as a box) and a ball of two
// shapes; upright it is free of both, leaning it hits the pillar (joint1 0.66, joint2 1.0).
TEST(CheckTool, StatesAgainstASceneFile) {
  const std::string scene = write_states(
      "pillar scene\n"
      "* pillar\n0.45 0.35 0.4\n0 0 0 1\n1\nbox\n0.12 0.12 0.8\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n"
      "* balls\n0 -0.6 0.3\n0 0 0 1\n2\nsphere\n0.05\n0 0 0\n0 0 0 1\n0 0 0 0\nsphere\n0.05\n0 0 0.2\n0 0 0 1\n0 0 0 0\n0\n"
      ".\n");
  const std::string states = write_states("joints: joint1 joint2\n0 0\n0.66 1.0\n");
  const std::vector<std::string> lines = output_lines(run({"--urdf", kUrdf, "--states", states, "--scene", scene, "--distance"}));
  ASSERT_EQ(lines.size(), 2u);
  const std::string& upright = lines[0];
  const std::string& leaning = lines[1];
  EXPECT_EQ(upright.rfind("0 free distance=", 0), 0u) << upright;
  EXPECT_EQ(leaning.rfind("1 collision ", 0), 0u) << leaning;
  EXPECT_NE(leaning.find(":pillar"), std::string::npos) << leaning;
  // Without the scene the same state is free: the pillar is what it hits.
  const ToolRun alone = run({"--urdf", kUrdf, "--states", states});
  EXPECT_NE(alone.out.find("1 free"), std::string::npos) << alone.out;
  // Upright, the nearest of the self pairs and the scene's objects is at a positive distance.
  EXPECT_GT(std::stod(upright.substr(upright.find("distance=") + 9)), 0.0) << upright;
  // A malformed scene: exit 1, the file, line and field named, nothing printed.
  const std::string bad = write_states("s\n* pillar\n0 0 0\n0 0 0 1\n1\nbox\n0.1 0 0.1\n0 0 0\n0 0 0 1\n0 0 0 0\n0\n.\n");
  const ToolRun refused = run({"--urdf", kUrdf, "--states", states, "--scene", bad});
  EXPECT_EQ(refused.code, 1);
  EXPECT_TRUE(refused.out.empty()) << refused.out;
  EXPECT_NE(refused.err.find(bad + ":7: object 'pillar' shape 1 (box) size 2 is not a positive number"), std::string::npos) << refused.err;
}

// A PlanningScene in YAML: its objects, and its robot state for the joints the states file leaves
// out (joint2 at 1.0 leans the arm into the pillar once joint1 turns it there).
TEST(CheckTool, StatesAgainstAYamlScene) {
  const std::string scene = write_states("") + ".yaml";
  std::ofstream(scene) << "name: pillar\n"
                          "robot_state:\n  joint_state: {name: [joint2, no_such_joint], position: [1.0, 3.0]}\n"
                          "world:\n  collision_objects:\n    - id: pillar\n      header: {frame_id: world}\n"
                          "      primitives: [{type: 1, dimensions: [0.12, 0.12, 0.8]}]\n"
                          "      primitive_poses: [{position: {x: 0.45, y: 0.35, z: 0.4}, orientation: {x: 0, y: 0, z: 0, w: 1}}]\n"
                          "allowed_collision_matrix: {entry_names: [pillar, hand, link1], entry_values: [{enabled: [false, true, false]}, "
                          "{enabled: [true, false, true]}, {enabled: [false, true, false]}]}\n";
  const std::string states = write_states("joints: joint1\n0\n0.66\n");
  const ToolRun r = run({"--urdf", kUrdf, "--states", states, "--scene", scene});
  const std::vector<std::string> lines = output_lines(r);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].rfind("0 free", 0), 0u) << lines[0];
  EXPECT_EQ(lines[1].rfind("1 collision ", 0), 0u) << lines[1];
  EXPECT_NE(lines[1].find(":pillar"), std::string::npos) << lines[1];
  EXPECT_NE(r.err.find("warning: the scene's robot state names 'no_such_joint'"), std::string::npos) << r.err;
  // (pillar, hand) names an object: applied, the hand may touch the pillar; (hand, link1) is the
  // robot's own pair: warned of.
  EXPECT_EQ(lines[1].find("hand:pillar"), std::string::npos) << lines[1];
  EXPECT_NE(r.err.find("warning: the scene's 1 allowed-collision entries for pairs of links are not applied"), std::string::npos) << r.err;
  std::filesystem::remove(scene);
}

TEST(CheckTool, PrintsTheMatrix) {
  const ToolRun r = run({"--urdf", kUrdf, "--print-acm"});
  ASSERT_EQ(r.code, 0) << r.err;
  EXPECT_NE(r.out.find("skip link1:link2 adjacent"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("check base_link:link3"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("tool_frame"), std::string::npos) << "links without geometry are not listed";
  // 10 links with geometry: 45 pairs, then the 10 solid links (boxes, cylinders, spheres) and no
  // open mesh.
  EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 55);
  EXPECT_NE(r.out.find("\nsolid base_link\n"), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find("\nopen "), std::string::npos) << r.out;
}

TEST(CheckTool, SampledPairsAndTheirCache) {
  const std::string cache = (fs::temp_directory_path() / ("bvh_tool_cache_" + std::to_string(::getpid()))).string();
  const ToolRun first = run({"--urdf", kUrdf, "--print-acm", "--sample-acm", "300", "--acm-cache", cache});
  ASSERT_EQ(first.code, 0) << first.err;
  EXPECT_NE(first.out.find(" never-collide"), std::string::npos) << first.out;
  ASSERT_TRUE(fs::exists(cache));
  const ToolRun second = run({"--urdf", kUrdf, "--print-acm", "--sample-acm", "300", "--acm-cache", cache});
  EXPECT_EQ(second.out, first.out) << "the cached matrix is the sampled one";
  fs::remove(cache);
}

TEST(CheckTool, ErrorsGoToStderrWithNonZeroExit) {
  for (const auto& [args, message] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"--urdf", kUrdf, "--states", write_states("joints: nonesuch\n0\n")}, "'nonesuch' is not a movable"},
           {{"--urdf", kUrdf, "--states", write_states("joints: joint1 joint2\n0.1\n")}, "1 values for 2 joints"},
           {{"--urdf", kUrdf, "--states", write_states("joints: joint1\nnan\n")}, "not a finite number"},
           {{"--urdf", kUrdf, "--states", write_states("0 0\n")}, "first line must be 'joints:"},
           {{"--urdf", "/missing.urdf", "--states", write_states("joints: joint1\n0\n")}, "/missing.urdf"},
           {{"--states", "x"}, "--urdf FILE is required"},
           {{"--urdf", kUrdf, "--tolerance", "-1", "--states", "x"}, "--tolerance needs a number"},
           {{"--bogus"}, "unknown argument '--bogus'"},
           // A joint named twice in the header, and counts out of their type's range.
           {{"--urdf", kUrdf, "--states", write_states("joints: joint1 joint1\n0 0\n")}, "joint 'joint1' is named twice"},
           {{"--urdf", kUrdf, "--print-acm", "--sample-acm", "99999999999999999999"}, "--sample-acm needs a whole number"},
           {{"--urdf", kUrdf, "--print-acm", "--sample-acm", "1.5"}, "--sample-acm needs a whole number"},
           {{"--urdf", kUrdf, "--print-acm", "--sample-acm", "0"}, "--sample-acm needs a whole number"},
           // A malformed robot: the message the node gives too (node_bad_robot.test).
           {{"--urdf", write_states("<robot name='r'><link name='a'><collision><geometry><cylinder radius='nan' length='1'/>"
                                    "</geometry></collision></link></robot>"),
             "--states", write_states("joints:\n\n")},
            "link 'a', collision element 1: <cylinder> attribute 'radius' is 'nan': not finite"},
           // Only regular files: /dev/zero is read forever, a directory is no file.
           {{"--urdf", "/dev/zero", "--states", write_states("joints: joint1\n0\n")}, "is not a regular file"},
           {{"--urdf", kUrdf, "--states", "/dev/zero"}, "is not a regular file"},
           {{"--urdf", kUrdf, "--srdf", "/tmp", "--states", write_states("joints: joint1\n0\n")}, "is not a regular file"}}) {
    const ToolRun r = run(args);
    EXPECT_NE(r.code, 0) << message;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
  }
}

// Issue 31, the three loader answers that were wrong, through the CLI as a user meets them.
// 1. A floating-base humanoid's SRDF, as MoveIt loads it: a <group_state> gives the virtual
//    joint all seven values in one attribute. It stopped the tool ("is not a finite number").
TEST(CheckTool, FloatingBaseGroupStateIsAccepted) {
  const std::string urdf = write_states(
      "<robot name='humanoid'><link name='base_link'><collision><geometry><box size='0.3 0.2 0.2'/></geometry></collision></link>"
      "<link name='leg'><collision><geometry><cylinder radius='0.05' length='0.6'/></geometry></collision></link>"
      "<joint name='hip' type='revolute'><parent link='base_link'/><child link='leg'/><origin xyz='0 0 -0.5'/>"
      "<axis xyz='0 1 0'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>");
  const std::string srdf = write_states(
      "<robot name='humanoid'>\n<virtual_joint name='root_joint' type='floating' parent_frame='world' child_link='base_link'/>\n"
      "<group name='all'/>\n<group_state name='half_sitting' group='all'>\n<joint name='root_joint' value='0. 0. 1.01927 0. 0. 0. 1.' />\n"
      "<joint name='hip' value='-0.4' />\n</group_state>\n</robot>\n");
  const ToolRun ok = run({"--urdf", urdf, "--srdf", srdf, "--states", write_states("joints: hip\n0.5\n")});
  EXPECT_EQ(ok.code, 0) << ok.err;
  EXPECT_EQ(ok.out, "0 free\n");
  EXPECT_TRUE(ok.err.empty()) << ok.err;
  // A wrong count is a warning that names it (MoveIt loads the robot and leaves the joint out of
  // the state): the tool goes on.
  const ToolRun odd = run({"--urdf", urdf, "--srdf",
                           write_states("<robot name='humanoid'><virtual_joint name='root_joint' type='floating' parent_frame='w' "
                                        "child_link='base_link'/><group name='all'/><group_state name='s' group='all'>"
                                        "<joint name='root_joint' value='0 0 1 0 0 1'/></group_state></robot>"),
                           "--states", write_states("joints: hip\n0.5\n")});
  EXPECT_EQ(odd.code, 0) << odd.err;
  EXPECT_EQ(odd.out, "0 free\n");
  EXPECT_NE(odd.err.find("warning: SRDF <group_state name=\"s\"> (line 1): joint 'root_joint' (floating) needs 7 values (x y z qx qy qz qw), got 6"),
            std::string::npos) << odd.err;
}

// 2. A robot without any collision geometry printed "0 free" and exited 0; the node answers every
//    query on it with an error. Same rule here: an error naming the robot.
TEST(CheckTool, RobotWithoutCollisionGeometryIsAnError) {
  const std::string urdf = write_states(
      "<robot name='ghost'><link name='a'/><link name='b'/><joint name='j' type='revolute'><parent link='a'/><child link='b'/>"
      "<axis xyz='0 0 1'/><limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>");
  for (const auto& args : std::vector<std::vector<std::string>>{{"--urdf", urdf, "--states", write_states("joints: j\n0\n")},
                                                                {"--urdf", urdf, "--print-acm"}}) {
    const ToolRun r = run(args);
    EXPECT_EQ(r.code, 1);
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_NE(r.err.find("robot 'ghost' has no collision geometry: there is nothing to check"), std::string::npos) << r.err;
  }
}

// 3. A mesh file name with a NUL character reference: tinyxml2 cut the name at the NUL and the
//    tool loaded the file before it. A control character in the name, referenced or written, is
//    an error naming the link and the element.
TEST(CheckTool, MeshFileNameWithAControlCharacterIsAnError) {
  const std::string stl = write_states(
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n");
  const std::string states = write_states("joints:\n\n");
  const ToolRun clean = run({"--urdf", write_states("<robot name='r'><link name='arm'><collision><geometry><mesh filename='file://" + stl +
                                                    "'/></geometry></collision></link></robot>"),
                             "--states", states});
  ASSERT_EQ(clean.code, 0) << clean.err << " (the file itself loads)";
  for (const std::string suffix : {"&#0;x", "&#x0;", "&#00;", "&#9;", "&#x1F;", "&#127;", "\x01"}) {
    const ToolRun r = run({"--urdf", write_states("<robot name='r'><link name='base'/><link name='arm'>"
                                                  "<collision><geometry><box size='1 1 1'/></geometry></collision>"
                                                  "<collision><geometry><mesh filename='file://" + stl + suffix +
                                                  "'/></geometry></collision></link><joint name='j' type='fixed'>"
                                                  "<parent link='base'/><child link='arm'/></joint></robot>"),
                           "--states", states});
    EXPECT_EQ(r.code, 1) << suffix;
    EXPECT_TRUE(r.out.empty()) << r.out;
    EXPECT_NE(r.err.find("link 'arm', collision element 2: <mesh> attribute 'filename' holds a control character"),
              std::string::npos) << r.err;
  }
}

// --help (and -h) print the usage with every option to stdout and exit 0, whatever else is given;
// it answered "unknown argument '--help'" with exit 1.
TEST(CheckTool, HelpPrintsTheUsageAndExitsZero) {
  for (const std::vector<std::string>& args : {std::vector<std::string>{"--help"}, {"-h"}, {"--urdf", kUrdf, "--help"}}) {
    const ToolRun r = run(args);
    EXPECT_EQ(r.code, 0) << r.err;
    EXPECT_TRUE(r.err.empty()) << r.err;
    for (const char* option : {"--urdf", "--srdf", "--states", "--scene", "--package-path", "--distance", "--print-acm",
                               "--tolerance", "--padding", "--sample-acm", "--acm-cache", "--help"}) {
      EXPECT_NE(r.out.find(option), std::string::npos) << option << " missing from:\n" << r.out;
    }
  }
}

// The public benchmark's panda SRDF gives its fixed finger joint a value in the state "close";
// MoveIt loads the robot and leaves that joint out of the state. We stopped: "SRDF <group_state
// name="close"> (line 102): joint 'panda_finger_joint1' (fixed) needs 0 values, got 1". Now a
// warning names it and the tool checks the states (the demo arm's hand joint is fixed).
TEST(CheckTool, AValueForAFixedJointInAGroupStateIsAWarning) {
  const std::string srdf = write_states(
      "<robot name='demo_arm'>\n<group name='hand'><joint name='hand_joint'/></group>\n"
      "<group_state name='close' group='hand'>\n<joint name='hand_joint' value='0'/>\n</group_state>\n</robot>\n");
  const ToolRun r = run({"--urdf", kUrdf, "--srdf", srdf, "--states", write_states("joints: joint2\n0\n")});
  EXPECT_EQ(r.code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("0 free", 0), 0u) << r.out;
  EXPECT_NE(r.err.find("warning: SRDF <group_state name=\"close\"> (line 4): joint 'hand_joint' (fixed) needs 0 values, got 1: "
                       "this state does not set it"),
            std::string::npos) << r.err;
}

}  // namespace
}  // namespace bvh_collision
