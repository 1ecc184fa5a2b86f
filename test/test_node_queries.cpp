// Launch test: the node on a robot (~urdf_file, started by the .test file the way a user starts
// it) answers check_state and check_states as the library does on the same files: free and
// self-colliding configurations, the colliding link pairs, distances and closest pairs, and
// joints left out of a request taken from joint_states.
#include <atomic>
#include <mutex>
#include <set>
#include <thread>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/topic.h>

#include "bvh_collision/CheckStates.h"
#include "node_test_client.h"

namespace bvh_collision::test {
namespace {

class NodeQueries : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string urdf;
    ASSERT_TRUE(ros::param::get("~urdf_file", urdf)) << "the .test file must set ~urdf_file";
    checker_ = new CollisionChecker(library_checker(urdf));
    ASSERT_TRUE(wait_for_node()) << "the node never advertised check_state";
  }
  static void TearDownTestSuite() { delete checker_; }
  const CollisionChecker& checker() const { return *checker_; }

  bool library_collides(const std::vector<double>& q) const { return checker().check_self(q.data()).collision; }
  double library_distance(const std::vector<double>& q) const {
    SelfCollisionRequest r;
    r.distance = true;
    return checker().check_self(q.data(), r).min_distance;
  }

  static CollisionChecker* checker_;
};
CollisionChecker* NodeQueries::checker_ = nullptr;

// The node comes up without proxies and builds its levels on a thread of its own, coarsest
// first; the diagnostics say which are in use. The .test file says which to expect (the default
// levels); the tests below then run with them.
TEST_F(NodeQueries, ProxyLevelsJoinAfterStartUp) {
  std::string expected;
  ASSERT_TRUE(ros::param::get("~expect_proxy_levels", expected)) << "the .test file must set ~expect_proxy_levels";
  // A deadline for the event: the levels take up to ~20 s to build on an idle machine (panda).
  EXPECT_EQ(wait_for_diagnostic("proxy levels ready (m)", [&](const std::string& v) { return v == expected; }, 300.0),
            expected);
}

TEST_F(NodeQueries, FreeAndSelfCollidingConfigurations) {
  std::mt19937_64 rng(11);
  const auto free = find_configuration(checker(), rng, [&](const auto& q) { return library_distance(q) > 0.02; });
  const auto hit = find_configuration(checker(), rng, [&](const auto& q) { return library_collides(q); });

  const auto a = call<CheckState>("check_state", state_request(checker(), free)).response;
  EXPECT_EQ(a.error, "");
  EXPECT_TRUE(a.valid);
  EXPECT_FALSE(a.self_collision);
  EXPECT_TRUE(std::isnan(a.min_distance)) << "distance was not asked for";

  auto request = state_request(checker(), hit, CheckState::Request::SELF);
  request.max_contacts = 1000;
  const auto b = call<CheckState>("check_state", request).response;
  EXPECT_EQ(b.error, "");
  EXPECT_FALSE(b.valid);
  EXPECT_TRUE(b.self_collision);
  EXPECT_FALSE(b.environment_collision) << "only SELF was asked for";
  // The contacts name exactly the pairs the library finds colliding.
  SelfCollisionRequest all;
  all.all_pairs = true;
  std::set<std::set<std::string>> expected, reported;
  const auto& links = checker().model().links();
  for (const auto& [i, j] : checker().check_self(hit.data(), all).colliding_pairs) {
    expected.insert({links[i].name, links[j].name});
  }
  for (const Contact& c : b.contacts) reported.insert({c.body_a, c.body_b});
  EXPECT_EQ(reported, expected);
  for (const Contact& c : b.contacts) {
    EXPECT_GE(c.depth, 0.0);
  }
}

// docs/design.md through the service, whatever serves the tolerance (the link proxies when
// the .test file builds them): collision whenever the exact distance is 0, free beyond it.
TEST_F(NodeQueries, TolerantAnswersKeepTheContract) {
  std::mt19937_64 rng(17);
  int colliding = 0, far = 0;
  for (int i = 0; i < 300; ++i) {
    const auto q = random_configuration(checker().model(), rng);
    const double d = library_distance(q);
    auto request = state_request(checker(), q, CheckState::Request::SELF);
    request.tolerance = 0.02;
    const auto r = call<CheckState>("check_state", request).response;
    ASSERT_EQ(r.error, "");
    if (d <= 0.0) {
      ++colliding;
      EXPECT_TRUE(r.self_collision) << "state " << i << " collides";
    }
    if (d > 0.02) {
      ++far;
      EXPECT_FALSE(r.self_collision) << "state " << i << " is " << d << " m from collision";
    }
  }
  EXPECT_GT(colliding, 0);
  EXPECT_GT(far, 0);
}

TEST_F(NodeQueries, DistancesMatchTheLibrary) {
  std::mt19937_64 rng(12);
  for (int i = 0; i < 25; ++i) {
    const auto q = random_configuration(checker().model(), rng);
    auto request = state_request(checker(), q, CheckState::Request::SELF);
    request.distance = true;
    const auto r = call<CheckState>("check_state", request).response;
    SelfCollisionRequest lib;
    lib.distance = true;
    const SelfCollisionResult expected = checker().check_self(q.data(), lib);
    ASSERT_EQ(r.error, "");
    EXPECT_NEAR(r.min_distance, expected.min_distance, 1e-9) << "configuration " << i;
    if (expected.closest_a >= 0 && expected.min_distance > 0.0) {
      ASSERT_EQ(r.closest_pair.size(), 2u);
      EXPECT_EQ(r.closest_pair[0], checker().model().links()[expected.closest_a].name);
      EXPECT_EQ(r.closest_pair[1], checker().model().links()[expected.closest_b].name);
    }
  }
}

TEST_F(NodeQueries, BatchAnswersEqualSingleAnswers) {
  std::mt19937_64 rng(13);
  const std::size_t n = checker().model().variable_count(), rows = 300;
  CheckStates::Request request;
  request.joint_names = checker().model().variable_names();
  std::vector<bool> expected;
  for (std::size_t r = 0; r < rows; ++r) {
    const auto q = random_configuration(checker().model(), rng);
    request.positions.insert(request.positions.end(), q.begin(), q.end());
    expected.push_back(!library_collides(q));
  }
  ASSERT_EQ(request.positions.size(), rows * n);
  for (std::uint8_t checks : {std::uint8_t(0), std::uint8_t(CheckStates::Request::SELF)}) {
    request.checks = checks;  // the environment is empty: both ask the same
    const auto res = call<CheckStates>("check_states", request).response;
    ASSERT_EQ(res.error, "");
    ASSERT_EQ(res.valid.size(), rows);
    std::size_t free = 0;
    for (std::size_t r = 0; r < rows; ++r) {
      EXPECT_EQ(bool(res.valid[r]), expected[r]) << "configuration " << r;
      free += expected[r];
    }
    EXPECT_GT(free, 0u);
    EXPECT_LT(free, rows) << "the batch should hold both answers";
  }
}

TEST_F(NodeQueries, JointsLeftOutComeFromJointStates) {
  std::mt19937_64 rng(14);
  const auto hit = find_configuration(checker(), rng, [&](const auto& q) { return library_collides(q); });
  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<sensor_msgs::JointState>("/joint_states", 1, true);
  // A robot publishes its state all the time (a state older than ~joint_state_timeout would be
  // refused, not used: node_faults.test): so does this test, every 20 ms, from a thread.
  std::mutex mutex;
  sensor_msgs::JointState msg = joint_state(checker().model().variable_names(), hit);
  msg.name.push_back("some_other_robots_joint");  // ignored, as other publishers' joints are
  msg.position.push_back(1.0);
  std::atomic<bool> stop{false};
  std::thread robot([&] {
    while (!stop) {
      {
        const std::lock_guard<std::mutex> lock(mutex);
        msg.header.stamp = ros::Time::now();
        pub.publish(msg);
      }
      ros::WallDuration(0.02).sleep();
    }
  });
  const auto current_collides = [&] { return !call<CheckState>("check_state", CheckState::Request()).response.valid; };
  const auto eventually = [](auto holds) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
    while (!holds() && ros::WallTime::now() < deadline) ros::WallDuration(0.05).sleep();
    return holds();
  };
  // The empty request is the current state: colliding once the node has the message.
  EXPECT_TRUE(eventually(current_collides)) << "the node did not take the configuration from joint_states";
  // Naming every joint overrides the current state.
  const auto free = find_configuration(checker(), rng, [&](const auto& q) { return library_distance(q) > 0.02; });
  EXPECT_TRUE(call<CheckState>("check_state", state_request(checker(), free)).response.valid);
  // Naming some joints keeps the others at their current (colliding) values: the same answer
  // as the library on the merged configuration.
  CheckState::Request partial;
  partial.state = joint_state({checker().model().variable_names()[0]}, {free[0]});
  std::vector<double> merged = hit;
  merged[0] = free[0];
  EXPECT_EQ(call<CheckState>("check_state", partial).response.valid, !library_collides(merged));
  // Back to a free current state for whoever runs next.
  {
    const std::lock_guard<std::mutex> lock(mutex);
    msg = joint_state(checker().model().variable_names(), free);
  }
  EXPECT_TRUE(eventually([&] { return !current_collides(); }));
  stop = true;
  robot.join();
}

}  // namespace
}  // namespace bvh_collision::test

int main(int argc, char** argv) { return bvh_collision::test::run_node_tests(argc, argv, "test_node_queries"); }
