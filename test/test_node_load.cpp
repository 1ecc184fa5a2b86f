// Launch test: load. Four clients call check_state and check_states for ~duration seconds (20 by
// default) while obstacle clouds stream at 10 Hz. No call may fail; latency percentiles are
// printed (and recorded in the test's XML) for each service.
#include <algorithm>
#include <atomic>
#include <cstdio>
#include <mutex>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>

#include "bvh_collision/CheckStates.h"
#include "bvh_collision/ros/conversions.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

struct Latencies {
  std::mutex mutex;
  std::vector<double> state, states;
  std::atomic<int> failures{0};
  std::string first_failure;
  void fail(const std::string& why) {
    std::lock_guard<std::mutex> lock(mutex);
    if (failures++ == 0) first_failure = why;
  }
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, std::size_t(q * v.size()))];
}

// A planner: persistent connections, random configurations, single and batched checks.
void client(int id, const CollisionChecker& checker, double seconds, Latencies& out) {
  ros::NodeHandle nh;
  auto single = nh.serviceClient<CheckState>(node_service("check_state"), true);
  auto batch = nh.serviceClient<CheckStates>(node_service("check_states"), true);
  std::mt19937_64 rng(100 + id);
  std::vector<double> mine_state, mine_states;
  const auto end = ros::WallTime::now() + ros::WallDuration(seconds);
  for (int call = 0; ros::WallTime::now() < end && ros::ok(); ++call) {
    const auto start = ros::WallTime::now();
    if (call % 4 != 3) {
      CheckState srv;
      srv.request = state_request(checker, random_configuration(checker.model(), rng));
      if (!single.call(srv) || !srv.response.error.empty()) out.fail("check_state: " + srv.response.error);
      mine_state.push_back((ros::WallTime::now() - start).toSec());
    } else {
      CheckStates srv;
      srv.request.joint_names = checker.model().variable_names();
      for (int r = 0; r < 50; ++r) {
        const auto q = random_configuration(checker.model(), rng);
        srv.request.positions.insert(srv.request.positions.end(), q.begin(), q.end());
      }
      if (!batch.call(srv) || !srv.response.error.empty() || srv.response.valid.size() != 50) {
        out.fail("check_states: " + srv.response.error);
      }
      mine_states.push_back((ros::WallTime::now() - start).toSec());
    }
  }
  std::lock_guard<std::mutex> lock(out.mutex);
  out.state.insert(out.state.end(), mine_state.begin(), mine_state.end());
  out.states.insert(out.states.end(), mine_states.begin(), mine_states.end());
}

// A depth camera in front of the robot: a 60 x 60 wall whose points jitter from frame to frame.
void stream_clouds(double seconds, std::atomic<int>& published) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 1);
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.01f, 0.01f);
  ros::WallRate rate(10.0);
  const auto end = ros::WallTime::now() + ros::WallDuration(seconds);
  while (ros::WallTime::now() < end && ros::ok()) {
    std::vector<ScanPoint> points;
    for (int i = 0; i < 60; ++i) {
      for (int j = 0; j < 60; ++j) points.emplace_back(0.9f + jitter(rng), -0.6f + 0.02f * i, 0.02f * j);
    }
    sensor_msgs::PointCloud2 cloud = to_cloud_msg(points, "base_link");
    cloud.header.stamp = ros::Time::now();
    pub.publish(cloud);
    ++published;
    rate.sleep();
  }
}

long long diagnostic(const std::string& key, double timeout) {
  const auto msg = ros::topic::waitForMessage<diagnostic_msgs::DiagnosticArray>("/diagnostics", ros::Duration(timeout));
  if (!msg) return -1;
  for (const auto& s : msg->status)
    for (const auto& kv : s.values)
      if (kv.key == key) return std::stoll(kv.value);
  return -1;
}

TEST(NodeLoad, FourClientsWhileCloudsStream) {
  std::string urdf;
  ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
  const double seconds = ros::param::param("~duration", 20.0);
  const CollisionChecker checker = library_checker(urdf);
  ASSERT_TRUE(wait_for_node());

  Latencies latencies;
  std::atomic<int> published{0};
  std::thread camera(stream_clouds, seconds, std::ref(published));
  std::vector<std::thread> clients;
  for (int i = 0; i < 4; ++i) clients.emplace_back(client, i, std::cref(checker), seconds, std::ref(latencies));
  for (auto& c : clients) c.join();
  camera.join();

  EXPECT_EQ(latencies.failures.load(), 0) << "first failure: " << latencies.first_failure;
  EXPECT_GT(latencies.state.size(), 100u);
  EXPECT_GT(latencies.states.size(), 30u);
  const long long inserted = diagnostic("clouds inserted", 3.0);
  // Clouds are queued one deep: a checker under load may skip some, but it must keep inserting.
  EXPECT_GE(inserted, published.load() / 4) << published.load() << " clouds published";

  const auto report = [&](const char* name, const std::vector<double>& v) {
    const double p50 = percentile(v, 0.5) * 1e3, p99 = percentile(v, 0.99) * 1e3;
    std::printf("load: %-13s %6zu calls  p50 %.3f ms  p99 %.3f ms\n", name, v.size(), p50, p99);
    testing::Test::RecordProperty(std::string(name) + "_calls", std::to_string(v.size()));
    testing::Test::RecordProperty(std::string(name) + "_p50_ms", std::to_string(p50));
    testing::Test::RecordProperty(std::string(name) + "_p99_ms", std::to_string(p99));
  };
  report("check_state", latencies.state);
  report("check_states50", latencies.states);
  std::printf("load: %d clouds published at 10 Hz, %lld inserted\n", published.load(), inserted);
  std::fflush(stdout);
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_load"); }
