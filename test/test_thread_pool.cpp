// The core's one executor (geometry/thread_pool.h): every index once, blocks spread over the
// participants, an exception reaching the caller (never std::terminate), a job started while the
// pool is lent out run by its caller alone; and a batch check whose worker throws.
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/robot/robot_description.h"
#include "robot_data.h"

namespace bvh_collision {
namespace {

TEST(ThreadPool, EveryIndexOnceOnEveryParticipant) {
  ThreadPool pool(3);
  EXPECT_EQ(pool.capacity(), 4u);
  std::vector<std::atomic<int>> seen(10007);
  std::vector<std::atomic<int>> by(4);
  std::atomic<int> calls{0};
  const unsigned n = pool.run(4, [&](unsigned participant) {
    ++calls;
    ++by[participant];
  });
  EXPECT_EQ(n, 4u);
  EXPECT_EQ(calls.load(), 4);
  for (const auto& b : by) {
    EXPECT_EQ(b.load(), 1);
  }
  pool.for_each(seen.size(), 7, [&](std::size_t i) { ++seen[i]; });
  for (std::size_t i = 0; i < seen.size(); ++i) {
    ASSERT_EQ(seen[i].load(), 1) << i;
  }
  pool.for_each(0, 7, [&](std::size_t) { FAIL() << "no work"; });
}

TEST(ThreadPool, AWorkersExceptionReachesTheCallerAndThePoolStaysUsable) {
  ThreadPool pool(3);
  for (int round = 0; round < 20; ++round) {
    std::atomic<std::size_t> done{0};
    EXPECT_THROW(pool.for_each(100000, 10,
                               [&](std::size_t i) {
                                 if (i == 50000) throw std::runtime_error("index 50000");
                                 ++done;
                               }),
                 std::runtime_error);
    EXPECT_LT(done.load(), 100000u) << "work stops after the exception";
    // Thrown by a worker, not the caller: participant 0 never throws here.
    EXPECT_THROW(pool.run(4,
                          [&](unsigned p) {
                            if (p == 3) throw std::invalid_argument("participant 3");
                          }),
                 std::invalid_argument);
  }
  std::atomic<int> after{0};
  pool.for_each(1000, 1, [&](std::size_t) { ++after; });
  EXPECT_EQ(after.load(), 1000);
}

TEST(ThreadPool, AJobStartedWhileThePoolIsLentOutRunsOnItsCaller) {
  ThreadPool pool(2);
  std::atomic<unsigned> inner_participants{0};
  std::atomic<int> inner_work{0};
  pool.run(3, [&](unsigned p) {
    if (p != 0) return;
    // Nested: the pool is busy with this very job.
    inner_participants = pool.run(3, [&](unsigned) { ++inner_work; });
  });
  EXPECT_EQ(inner_participants.load(), 1u);
  EXPECT_EQ(inner_work.load(), 1);
  // Two callers at once: both finish, all work done.
  std::atomic<int> total{0};
  std::thread other([&] { pool.for_each(5000, 3, [&](std::size_t) { ++total; }); });
  pool.for_each(5000, 3, [&](std::size_t) { ++total; });
  other.join();
  EXPECT_EQ(total.load(), 10000);
}

// A node's map updates run behind its queries: a thread given a background pool finds it as
// shared(), every participant of its jobs runs at the pool's nice value, and other threads keep
// the process's pool and their own priority.
TEST(ThreadPool, ABackgroundThreadsFanOutsRunAtItsPriority) {
  errno = 0;
  const int base = getpriority(PRIO_PROCESS, 0);
  ASSERT_EQ(errno, 0);
  const int background_nice = std::min(19, base + 7);
  ThreadPool background(2, background_nice);
  std::vector<int> nice_of(3, -100);
  bool found_background = false;
  unsigned participants = 0;
  std::thread updater([&] {
    ASSERT_TRUE(ThreadPool::lower_this_thread(background_nice));
    ThreadPool::use_on_this_thread(&background);
    found_background = &ThreadPool::shared() == &background;
    std::atomic<unsigned> arrived{0};
    participants = ThreadPool::shared().run(3, [&](unsigned p) {
      ++arrived;
      while (arrived.load() < 3) std::this_thread::yield();  // all three at once: the workers take part
      nice_of[p] = getpriority(PRIO_PROCESS, 0);
    });
  });
  updater.join();
  EXPECT_TRUE(found_background);
  ASSERT_EQ(participants, 3u);
  for (const int nice : nice_of) EXPECT_EQ(nice, background_nice);
  EXPECT_NE(&ThreadPool::shared(), &background) << "another thread keeps the process's pool";
  EXPECT_EQ(getpriority(PRIO_PROCESS, 0), base) << "and its priority";
  EXPECT_TRUE(ThreadPool::lower_this_thread(base)) << "no change asked: nothing to refuse";
}

// A batch whose states throw inside the workers (a root pose that is not rigid): the caller gets
// std::invalid_argument; before the shared pool this ended in std::terminate.
TEST(ThreadPool, ABatchWhoseWorkerThrowsReportsTheError) {
  RobotModel model = RobotModel::from_urdf(*load_robot_description_file(test::source_dir() + "/urdf/demo_arm.urdf"),
                                           PackageResolver({}));
  AllowedCollisionMatrix acm = AllowedCollisionMatrix::adjacent_links(model);
  const CollisionChecker checker(std::move(model), std::move(acm));
  const Environment env(0.05);
  const std::vector<double> states(checker.model().variable_count() * 500, 0.1);
  BatchRequest request;
  request.root_pose.t = Vec3(std::nan(""), 0, 0);
  EXPECT_THROW(checker.check_batch(states.data(), 500, &env, request), std::invalid_argument);
  request.root_pose = Transform::Identity();
  const std::vector<char> ok = checker.check_batch(states.data(), 500, &env, request);
  EXPECT_EQ(ok.size(), 500u);
}

}  // namespace
}  // namespace bvh_collision
