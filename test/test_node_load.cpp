// Launch test: load. Four clients make ~calls calls each (check_state and check_states of 50)
// while obstacle clouds stream at 10 Hz until they are done. No call may fail, every batch
// answers each of its states, and every cloud sent is accounted for: inserted, or superseded by
// a newer one while the node was busy (never dropped for a missing pose or state: the robot
// stands still). Counts, not rates: a busy machine takes longer, not fewer. Latency
// percentiles are printed (and recorded in the test's XML); make bench measures them.
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
void client(int id, const CollisionChecker& checker, int calls, Latencies& out) {
  ros::NodeHandle nh;
  auto single = nh.serviceClient<CheckState>(node_service("check_state"), true);
  auto batch = nh.serviceClient<CheckStates>(node_service("check_states"), true);
  std::mt19937_64 rng(100 + id);
  std::vector<double> mine_state, mine_states;
  for (int call = 0; call < calls && ros::ok(); ++call) {
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

// A depth camera in front of the robot: a 60 x 60 wall whose points jitter from frame to frame,
// at 10 Hz until `done`, at least `at_least` clouds.
void stream_clouds(const std::atomic<bool>& done, int at_least, std::atomic<int>& published) {
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("/obstacle_cloud", 10);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline) ros::WallDuration(0.05).sleep();
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> jitter(-0.01f, 0.01f);
  ros::WallRate rate(10.0);
  while ((!done || published < at_least) && ros::ok()) {
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

TEST(NodeLoad, FourClientsWhileCloudsStream) {
  std::string urdf;
  ASSERT_TRUE(ros::param::get("~urdf_file", urdf));
  const int calls = ros::param::param("~calls", 300);
  const CollisionChecker checker = library_checker(urdf);
  ASSERT_TRUE(wait_for_node());

  Latencies latencies;
  std::atomic<int> published{0};
  std::atomic<bool> done{false};
  std::thread camera(stream_clouds, std::cref(done), 20, std::ref(published));
  std::vector<std::thread> clients;
  for (int i = 0; i < 4; ++i) clients.emplace_back(client, i, std::cref(checker), calls, std::ref(latencies));
  for (auto& c : clients) c.join();
  done = true;
  camera.join();

  EXPECT_EQ(latencies.failures.load(), 0) << "first failure: " << latencies.first_failure;
  EXPECT_EQ(latencies.state.size() + latencies.states.size(), 4u * calls);
  const CloudCounts clouds = wait_for_clouds(published.load());
  EXPECT_GT(clouds.inserted, 0u) << "the node must keep inserting under load";
  EXPECT_EQ(clouds.inserted + clouds.superseded, static_cast<std::uint64_t>(published.load()))
      << "a cloud is inserted, or superseded while the node was busy: no other reason applies here";

  const auto report = [&](const char* name, const std::vector<double>& v) {
    const double p50 = percentile(v, 0.5) * 1e3, p99 = percentile(v, 0.99) * 1e3;
    std::printf("load: %-13s %6zu calls  p50 %.3f ms  p99 %.3f ms\n", name, v.size(), p50, p99);
    testing::Test::RecordProperty(std::string(name) + "_calls", std::to_string(v.size()));
    testing::Test::RecordProperty(std::string(name) + "_p50_ms", std::to_string(p50));
    testing::Test::RecordProperty(std::string(name) + "_p99_ms", std::to_string(p99));
  };
  report("check_state", latencies.state);
  report("check_states50", latencies.states);
  std::printf("load: %d clouds published at 10 Hz, %llu inserted, %llu superseded\n", published.load(),
              static_cast<unsigned long long>(clouds.inserted), static_cast<unsigned long long>(clouds.superseded));
  std::fflush(stdout);
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_load"); }
