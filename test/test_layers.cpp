// The architecture of docs/design.md, checked on the sources: every file belongs to one layer,
// lower layers never include higher ones, the library includes no ROS header (and OctoMap only
// in octomap_bridge), and the built libraries link no ROS library.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
const std::string kSource = BVH_COLLISION_SOURCE_DIR;

// Which project layers each folder may include (its own included): the parts along the data flow
// of docs/design.md, each a library of its own.
const std::set<std::string> kBelowWorld = {"geometry", "bvh", "octree", "narrowphase"};
std::set<std::string> with(std::set<std::string> layers, std::initializer_list<std::string> more) {
  layers.insert(more);
  return layers;
}
const std::map<std::string, std::set<std::string>> kAllowed = {
    {"geometry", {"geometry"}},
    {"bvh", {"geometry", "bvh"}},
    {"octree", {"geometry", "octree"}},
    {"robot", {"geometry", "bvh", "robot"}},
    {"narrowphase", {"geometry", "bvh", "octree", "narrowphase"}},
    {"world", with(kBelowWorld, {"world"})},
    {"model", with(kBelowWorld, {"robot", "world", "model"})},
    {"query", with(kBelowWorld, {"robot", "world", "model", "query"})},
    {"io", with(kBelowWorld, {"world", "io"})},
    {"session", with(kBelowWorld, {"robot", "world", "model", "query", "io", "session"})},
    {"planning", with(kBelowWorld, {"robot", "world", "model", "query", "planning"})},
    {"ros", with(kBelowWorld, {"robot", "world", "model", "query", "io", "session", "planning", "ros"})},
    // The in-process Python module: an adapter over the core as ros is, with no ROS include.
    {"python", with(kBelowWorld, {"robot", "world", "model", "query", "io", "session", "python"})},
    {"nodes", with(kBelowWorld, {"robot", "world", "model", "query", "io", "session", "planning", "ros"})},
};
// The ROS-free library (everything below planning and ros).
const std::set<std::string> kCore = {"geometry", "bvh", "octree", "robot", "narrowphase", "world", "model", "query", "io", "session"};

struct Include {
  std::string file;
  int line;
  std::string target;
};

std::vector<Include> includes_of(const fs::path& file) {
  static const std::regex re(R"(^\s*#\s*include\s*[<"]([^>"]+)[>"])");
  std::vector<Include> out;
  std::ifstream in(file);
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    std::smatch m;
    if (std::regex_search(text, m, re)) out.push_back({file.string(), line, m[1]});
  }
  return out;
}

// Source files by layer: include/bvh_collision/<layer>/ and src/<layer>/.
std::map<std::string, std::vector<fs::path>> files_by_layer() {
  std::map<std::string, std::vector<fs::path>> out;
  for (const std::string root : {"include/bvh_collision", "src"}) {
    const fs::path dir = fs::path(kSource) / root;
    if (!fs::exists(dir)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      if (!entry.is_regular_file()) continue;
      const fs::path rel = fs::relative(entry.path(), dir);
      const std::string layer = rel.begin()->string();
      out[layer].push_back(entry.path());
    }
  }
  return out;
}

bool is_ros_header(const std::string& target) {
  static const std::regex re(
      R"(^(ros|tf2_ros|tf2|rosbag|message_filters|diagnostic_updater|[a-z_]*_msgs|std_srvs|xmlrpcpp)/)");
  // Generated bvh_collision messages live directly under bvh_collision/ (no layer folder).
  static const std::regex generated(R"(^bvh_collision/[A-Z][A-Za-z]*\.h$)");
  return std::regex_search(target, re) || std::regex_match(target, generated);
}

TEST(Layers, EveryFileIsInALayerFolder) {
  for (const auto& [layer, files] : files_by_layer()) {
    EXPECT_TRUE(kAllowed.count(layer)) << "files outside any layer folder: " << files.front();
  }
}

TEST(Layers, LowerLayersNeverIncludeHigherOnes) {
  const auto layers = files_by_layer();
  ASSERT_FALSE(layers.empty()) << "no sources found under " << kSource;
  for (const auto& [layer, files] : layers) {
    if (!kAllowed.count(layer)) continue;
    for (const auto& file : files) {
      for (const Include& inc : includes_of(file)) {
        static const std::regex project(R"(^bvh_collision/([a-z_]+)/)");
        std::smatch m;
        if (!std::regex_search(inc.target, m, project)) continue;
        EXPECT_TRUE(kAllowed.at(layer).count(m[1])) << inc.file << ":" << inc.line << " (layer "
                                                    << layer << ") includes " << inc.target;
      }
    }
  }
}

// The planning adapter is ROS-free too (a planner without ROS links it); OMPL only there.
TEST(Layers, PlanningIncludesNoRosHeaderAndOnlyItIncludesOmpl) {
  const auto layers = files_by_layer();
  ASSERT_TRUE(layers.count("planning")) << "no planning layer (planning/ompl_validity.h)";
  for (const auto& [layer, files] : layers) {
    for (const auto& file : files) {
      for (const Include& inc : includes_of(file)) {
        if (layer == "planning") {
          EXPECT_FALSE(is_ros_header(inc.target)) << inc.file << ":" << inc.line << " includes " << inc.target;
        }
        if (kCore.count(layer)) {
          EXPECT_NE(inc.target.rfind("ompl/", 0), 0u) << inc.file << ":" << inc.line << ": OMPL in the core";
        }
      }
    }
  }
}

TEST(Layers, CoreIncludesNoRosHeaderAndOctomapOnlyInTheBridge) {
  for (const auto& [layer, files] : files_by_layer()) {
    if (!kCore.count(layer)) continue;
    for (const auto& file : files) {
      for (const Include& inc : includes_of(file)) {
        EXPECT_FALSE(is_ros_header(inc.target)) << inc.file << ":" << inc.line << " includes "
                                                << inc.target << " in the ROS-free core";
        EXPECT_FALSE(inc.target.rfind("fcl/", 0) == 0 || inc.target.rfind("CGAL/", 0) == 0)
            << inc.file << ":" << inc.line << ": FCL and CGAL are test oracles, not core deps";
        if (inc.target.rfind("octomap/", 0) == 0) {
          EXPECT_NE(file.filename().string().find("octomap_bridge"), std::string::npos)
              << inc.file << ":" << inc.line << ": only octomap_bridge may include OctoMap";
        }
      }
    }
  }
}

// One dispatch over the kinds of collidable things, in narrowphase/: above it no code tests what
// kind a shape is (a primitive's kind, a mesh index or pointer), it hands the shape to the engine.
// The one exception is where the world model turns a described object (ObjectShape) into the
// engine's geometry: world/environment.h and .cpp; and io/scene_file.cpp and
// scene_yaml_write.cpp, which write a described object as MoveIt's .scene text or YAML, may read
// the description's kind (and nothing more).
std::vector<std::string> kind_tests_in(const fs::path& file) {
  static const std::vector<std::regex> kinds = {
      std::regex(R"(Primitive::Kind::)"), std::regex(R"(ShapeKind::)"), std::regex(R"(\.mesh\s*(>=|<|>)\s*-?[01]\b)"),
      std::regex(R"(\bmesh(\.get\(\))?\s*(==|!=)\s*nullptr)"), std::regex(R"(!\s*[\w.>-]*\bmesh\b\s*(\)|\|\||&&|\?))"),
      std::regex(R"([\w.>-]*\bmesh\s*\?)")};
  static const std::regex described(R"(ObjectShape::Kind::)");
  const bool world_model = file.filename() == "environment.cpp" || file.filename() == "environment.h";
  const bool describes = world_model || file.filename() == "scene_file.cpp" || file.filename() == "scene_yaml_write.cpp";
  std::vector<std::string> out;
  std::ifstream in(file);
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    const std::string code = text.substr(0, text.find("//"));
    bool found = !describes && std::regex_search(code, described);
    for (const std::regex& re : kinds) found = found || (!world_model && std::regex_search(code, re));
    if (found) out.push_back(file.string() + ":" + std::to_string(line) + ": " + text);
  }
  return out;
}

TEST(Layers, NoShapeKindTestAboveTheNarrowphase) {
  const auto layers = files_by_layer();
  ASSERT_TRUE(layers.count("narrowphase")) << "no narrowphase layer";
  std::size_t scanned = 0;
  for (const std::string layer : {"world", "model", "query", "io", "session", "planning", "ros", "nodes"}) {
    if (!layers.count(layer)) continue;
    for (const auto& file : layers.at(layer)) {
      ++scanned;
      for (const std::string& hit : kind_tests_in(file)) ADD_FAILURE() << "a kind test outside narrowphase/: " << hit;
    }
  }
  EXPECT_GT(scanned, 40u);
}

TEST(Layers, KindTestFinderFindsTheFormsItLooksFor) {
  // The check above is only as good as this finder: the forms the old dispatch by hand used.
  const fs::path probe = fs::temp_directory_path() / "bvh_collision_kind_probe.cpp";
  {
    std::ofstream out(probe);
    out << "if (s.mesh >= 0) {}\n"
        << "} else if (s.primitive.kind != Primitive::Kind::kSphere) {\n"
        << "if (!object.mesh) {\n"
        << "s.primitive = o.mesh == nullptr || o.shape.kind == ObjectShape::Kind::kBox;\n"
        << "x = o.mesh ? 1 : 2;\n"
        << "const double d = inscribed_depth(prim, p);  // a plain call: no kind test\n"
        << "// if (s.mesh < 0) in a comment is not code\n";
  }
  const std::vector<std::string> hits = kind_tests_in(probe);
  fs::remove(probe);
  ASSERT_EQ(hits.size(), 5u);
  EXPECT_NE(hits[0].find(":1:"), std::string::npos);
  EXPECT_NE(hits[4].find(":5:"), std::string::npos);
}

// No file of code over 600 lines (issue 34): a file that grows past it holds two things, and
// each gets its own (a test's cases in a second file of the same binary, as test_scene_motion.cpp).
TEST(Layers, NoFileOfCodeOverSixHundredLines) {
  std::size_t files = 0;
  for (const std::string root : {"include", "src", "test", "bench", "scripts"}) {
    const fs::path dir = fs::path(kSource) / root;
    ASSERT_TRUE(fs::exists(dir)) << dir;
    for (const auto& entry : fs::recursive_directory_iterator(dir)) {
      const std::string ext = entry.path().extension().string();
      if (!entry.is_regular_file() || (ext != ".cpp" && ext != ".h" && ext != ".py" && ext != ".sh")) continue;
      std::ifstream in(entry.path());
      std::size_t lines = 0;
      for (std::string line; std::getline(in, line);) ++lines;
      EXPECT_LE(lines, 600u) << entry.path();
      ++files;
    }
  }
  EXPECT_GT(files, 200u);  // the walk found the sources
}

TEST(Layers, IncludeCheckRecognisesRosHeaders) {
  // The check above is only as good as this classifier.
  EXPECT_TRUE(is_ros_header("ros/ros.h"));
  EXPECT_TRUE(is_ros_header("sensor_msgs/PointCloud2.h"));
  EXPECT_TRUE(is_ros_header("tf2_ros/buffer.h"));
  EXPECT_TRUE(is_ros_header("bvh_collision/CheckState.h"));
  EXPECT_FALSE(is_ros_header("bvh_collision/robot/robot_description.h"));
  EXPECT_FALSE(is_ros_header("urdf_model/model.h"));
  EXPECT_FALSE(is_ros_header("Eigen/Core"));
}

// Each of the library's parts, built: it links no ROS library (and the core links urdfdom).
TEST(Layers, TheLibrariesLinkNoRosLibrary) {
  std::istringstream list(BVH_COLLISION_LIBRARIES);
  std::size_t checked = 0;
  for (std::string lib; std::getline(list, lib, ':');) {
    ASSERT_TRUE(fs::exists(lib)) << lib;
    FILE* pipe = popen(("ldd '" + lib + "' 2>&1").c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string output;
    std::array<char, 512> buf{};
    while (fgets(buf.data(), buf.size(), pipe) != nullptr) output += buf.data();
    ASSERT_EQ(pclose(pipe), 0) << output;
    EXPECT_NE(output.find("liburdfdom_model"), std::string::npos) << "ldd output unexpected:\n" << output;
    static const std::regex ros_lib(
        R"(lib(roscpp|rosconsole|rostime|cpp_common|xmlrpcpp|tf2|tf2_ros|message_filters|roslib)[._])");
    EXPECT_FALSE(std::regex_search(output, ros_lib)) << lib << " links ROS:\n" << output;
    ++checked;
  }
  EXPECT_EQ(checked, 6u);
}

// make demo builds the `all` target only (make build-node): the node, its libraries and the
// demo's programs. Tests and benchmarks build under make test and make bench (a fresh machine's
// make demo took over 10 minutes when they were in it). A dry run of `all` lists what it compiles.
TEST(Build, TheDemoBuildCompilesNoTestNorBenchmark) {
  const std::string command = std::string("make -C '") + BVH_COLLISION_BINARY_DIR + "' -nB all 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  ASSERT_NE(pipe, nullptr);
  std::string out;
  char buffer[4096];
  for (std::size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) out.append(buffer, n);
  ASSERT_EQ(pclose(pipe), 0) << command;
  const std::string source = std::string(" -c ") + BVH_COLLISION_SOURCE_DIR + "/";
  std::istringstream lines(out);
  int compiled = 0;
  std::set<std::string> programs;
  for (std::string line; std::getline(lines, line);) {
    const std::size_t at = line.find(source);
    if (at == std::string::npos) continue;
    ++compiled;
    const std::string file = line.substr(at + source.size(), line.find(' ', at + source.size()) - at - source.size());
    EXPECT_NE(file.rfind("test/", 0), 0u) << "make demo compiles the test file " << file;
    EXPECT_NE(file.rfind("bench/", 0), 0u) << "make demo compiles the benchmark " << file;
    if (file.rfind("src/nodes/", 0) == 0) programs.insert(file);
  }
  EXPECT_GT(compiled, 20) << "the dry run listed no compilation:\n" << out.substr(0, 2000);
  for (const char* program : {"src/nodes/collision_checker.cpp", "src/nodes/demo_scene_publisher.cpp",
                              "src/nodes/demo_client.cpp", "src/nodes/plan_demo.cpp"}) {
    EXPECT_TRUE(programs.count(program)) << program << " is not in make demo's build";
  }
}

}  // namespace
