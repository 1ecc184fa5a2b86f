// The report generator on small inputs, so that `make bench`'s report cannot silently rot: every
// benchmark with --quick, the service benchmark on a private master, then scripts/bench_report.py.
// The report must have its eight sections and every plot it links; and the generator must refuse
// figures that break docs/design.md (a false negative, a distance beyond its allowed error, a
// restriction of the checked pairs that changes an answer).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "robot_data.h"

namespace bvh_collision {
namespace {

namespace fs = std::filesystem;

int run(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string report_command(const fs::path& dir) {
  return "PATH=/usr/bin:$PATH python3 " + test::source_dir() + "/scripts/bench_report.py " + dir.string() + " --quick";
}

class BenchReport : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::temp_directory_path() / ("bvh_collision_report_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const char* bench : {BENCH_SELF_COLLISION, BENCH_MESH_PAIR, BENCH_ENVIRONMENT, BENCH_STABILITY, BENCH_PLANNING, BENCH_SCENE_SCALE,
                              BENCH_PROXY_BUILD}) {
      const std::string log = (dir_ / (fs::path(bench).filename().string() + ".md")).string();
      statuses_.push_back(run(std::string(bench) + " " + dir_.string() + " --quick > " + log + " 2>&1"));
    }
    statuses_.push_back(run("BENCH_QUICK=true bash " + test::source_dir() + "/scripts/bench_node.sh " + dir_.string() +
                            " > " + (dir_ / "bench_node.log").string() + " 2>&1"));
    report_status_ = run(report_command(dir_) + " > " + (dir_ / "report.log").string() + " 2>&1");
  }
  static void TearDownTestSuite() {
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_);
  }
  static fs::path dir_;
  static std::vector<int> statuses_;
  static int report_status_;
};

fs::path BenchReport::dir_;
std::vector<int> BenchReport::statuses_;
int BenchReport::report_status_ = -1;

TEST_F(BenchReport, EveryBenchmarkRunsOnSmallInputs) {
  BVH_REQUIRE_ROBOTS();
  const char* names[] = {"self_collision", "mesh_pair", "environment", "stability", "planning", "scene_scale", "proxy_build", "node"};
  ASSERT_EQ(statuses_.size(), 8u);
  for (std::size_t i = 0; i < statuses_.size(); ++i) {
    EXPECT_EQ(statuses_[i], 0) << names[i] << ": see " << dir_;
  }
}

TEST_F(BenchReport, ReportHasEverySectionAndEveryPlotItLinks) {
  BVH_REQUIRE_ROBOTS();
  ASSERT_EQ(report_status_, 0) << read(dir_ / "report.log");
  const std::string report = read(dir_ / "report.md");
  EXPECT_NE(report.find("Measured "), std::string::npos);
  EXPECT_LT(report.find(" cores, g++ "), report.find("## 1.")) << "the machine's description is on top";
  EXPECT_LT(report.find("widest SIMD: "), report.find("## 1.")) << "the CPU's SIMD, named on top";
  EXPECT_LT(report.find("proxy batch kernel: "), report.find("## 1.")) << "the path the SIMD kernel took, named on top";
  EXPECT_LT(report.find("scans' ray walk: "), report.find("## 1.")) << "the path the scans' walk took, named on top";
  for (const char* section : {"## 1. Self-collision", "## 2. Distance", "## 3. Volume types", "## 4. Environment",
                              "## 5. Model only what the scene needs", "## 6. Service", "## 7. Planning",
                              "## 8. Numerical stability"}) {
    EXPECT_NE(report.find(section), std::string::npos) << section;
  }
  for (const char* robot : {"panda", "ur5e", "pr2", "demo"}) {
    EXPECT_NE(report.find(std::string("**") + robot + ": boolean self-collision against tolerance**"), std::string::npos)
        << robot;
  }
  EXPECT_NE(report.find("Link proxies built at a first start"), std::string::npos) << "the table proxy_build";
  EXPECT_NE(report.find("Python in-process (bvh_collision.Checker) against the C++ call and the rospy service"),
            std::string::npos)
      << "the table python";
  for (const char* robot : {"demo_arm", "panda"}) {
    EXPECT_NE(report.find(std::string("A live world through the services: certified motions while a camera's clouds arrive (") +
                          robot + ")"),
              std::string::npos)
        << robot;
  }
  EXPECT_EQ(report.find("nan"), std::string::npos) << "a figure that is not a number";
  const std::regex link(R"(\]\((plots/[a-z_]+\.png)\))");
  int plots = 0;
  for (auto it = std::sregex_iterator(report.begin(), report.end(), link); it != std::sregex_iterator(); ++it, ++plots) {
    const fs::path png = dir_ / (*it)[1].str();
    ASSERT_TRUE(fs::exists(png)) << png;
    EXPECT_GT(fs::file_size(png), 10000u) << png;
    EXPECT_EQ(read(png).substr(1, 3), "PNG") << png;
  }
  EXPECT_EQ(plots, 6);
}

// The live world through the services (issue 58): the clouds reached the node while the motions
// were timed, at every rate asked, for both robots; every call answered (an error fails the run).
TEST_F(BenchReport, TheServiceLiveWorldInsertsCloudsWhileMotionsAreTimed) {
  BVH_REQUIRE_ROBOTS();
  for (const char* robot : {"demo_arm", "panda"}) {
    const nlohmann::json t =
        nlohmann::json::parse(read(dir_ / "tables" / (std::string("live_world_service_") + robot + ".json")));
    const auto col = [&](const char* name) {
      const auto& c = t["columns"];
      return static_cast<std::size_t>(std::find(c.begin(), c.end(), name) - c.begin());
    };
    ASSERT_EQ(t["rows"].size(), 6u) << robot << ": check_motion and check_motions at 0, 10 and 30 Hz";
    for (const auto& row : t["rows"]) {
      const double rate = row[col("clouds Hz")].get<double>();
      EXPECT_GT(row[col("calls")].get<double>(), 0.0) << robot;
      if (rate > 0.0) {
        EXPECT_GT(row[col("clouds inserted per s")].get<double>(), 0.0) << robot << " at " << rate << " Hz";
      }
    }
  }
}

// A copy of the run's tables with one figure changed: the generator must refuse it.
void expect_refused(const fs::path& dir, const std::string& table, const std::string& column, double value,
                    const std::string& reason, std::size_t row = 1) {
  const fs::path copy = dir.string() + "_" + table;
  fs::remove_all(copy);
  fs::create_directories(copy);
  fs::copy(dir / "tables", copy / "tables");
  const fs::path file = copy / "tables" / (table + ".json");
  nlohmann::json t = nlohmann::json::parse(read(file));
  const auto& columns = t["columns"];
  const auto at = std::find(columns.begin(), columns.end(), column) - columns.begin();
  ASSERT_LT(at, static_cast<long>(columns.size())) << column;
  ASSERT_LT(row, t["rows"].size());
  t["rows"][row][at] = value;
  std::ofstream(file) << t.dump();
  const fs::path log = copy / "report.log";
  EXPECT_NE(run(report_command(copy) + " > " + log.string() + " 2>&1"), 0) << table << " " << column;
  EXPECT_NE(read(log).find(reason), std::string::npos) << read(log);
  EXPECT_FALSE(fs::exists(copy / "report.md"));
  fs::remove_all(copy);
}

TEST_F(BenchReport, GeneratorRefusesFiguresThatBreakTheSemantics) {
  BVH_REQUIRE_ROBOTS();
  ASSERT_EQ(report_status_, 0);
  expect_refused(dir_, "self_tolerance_ur5e", "false negatives", 1, "false negatives");
  expect_refused(dir_, "self_distance_pr2", "ours beyond the bound", 2, "allowed error");
  expect_refused(dir_, "stability_scale", "ours wrong answers", 1, "scale sweep");
  expect_refused(dir_, "stability_cylinders", "ours", 1, "cylinder case");
  expect_refused(dir_, "scene_model_pr2", "wrong answers", 1, "only moved pairs", 4);
  expect_refused(dir_, "speed_error", "false_negatives", 1, "speed_error: a false negative", 9);
  expect_refused(dir_, "proxy_proof", "beyond the tolerance", 1, "proxy_proof: a proxy level broke", 1);
  expect_refused(dir_, "planning", "paths colliding (FCL every 1e-3 rad)", 1, "planning: a path planned through our checker", 1);
}

}  // namespace
}  // namespace bvh_collision
