// One executor for every fan-out of the core (batch checks, the self filter, scan insertion, pair
// sampling): a fixed set of worker threads that a caller borrows for one job at a time.
//
// Bounded: the shared pool holds one thread per core less one (the caller works too), created
// once; no query starts threads of its own. A job that arrives while another one holds the pool
// (a second service thread, or a job started from inside a job) is run by its caller alone: it
// never waits for the pool and never deadlocks. An exception thrown by any participant stops the
// others taking more work and reaches the caller, rethrown from run(): never std::terminate.
//
// Background work (a node's map updates) gets a pool of its own at a lower priority: a thread
// that calls use_on_this_thread() finds that pool as shared(), so the core's fan-outs on that
// thread run on workers the scheduler puts behind the queries' threads, and never borrow the
// process pool a query would take.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace bvh_collision {

class ThreadPool {
 public:
  // `workers` threads besides the caller, each at `nice` (Linux: a thread's own nice value, 0 to
  // 19; only ever lowered, which needs no privilege).
  explicit ThreadPool(unsigned workers, int nice = 0);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  // The process's pool: hardware_concurrency() - 1 workers; on a thread that called
  // use_on_this_thread(), the pool it gave.
  static ThreadPool& shared();
  // Makes `pool` this thread's shared() (null: the process's pool again). The pool must outlive
  // the thread's use of it.
  static void use_on_this_thread(ThreadPool* pool);
  // Lowers the calling thread's priority to `nice` (0 to 19; a value at or below the thread's
  // own changes nothing). False when the system refused.
  static bool lower_this_thread(int nice);

  // The most participants a job can have: the workers and the caller.
  unsigned capacity() const { return static_cast<unsigned>(threads_.size()) + 1; }

  // Calls body(participant) once for each participant 0 .. n - 1 (0 is the caller), concurrently,
  // with n = min(participants, capacity()), or n = 1 when the pool is busy. Returns that n once
  // every call has returned, or rethrows the first exception any of them threw.
  unsigned run(unsigned participants, const std::function<void(unsigned participant)>& body);

  // fn(i) for every i in [0, count), in blocks of `block` taken as participants come free (costs
  // that differ by orders of magnitude still spread evenly); after an exception no new block
  // starts, and the exception is rethrown. `participants` 0: as many as the pool has.
  template <class Fn>
  void for_each(std::size_t count, std::size_t block, Fn&& fn, unsigned participants = 0) {
    if (count == 0) return;
    block = block == 0 ? 1 : block;
    const std::size_t blocks = (count + block - 1) / block;
    const unsigned wanted = participants == 0 ? capacity() : participants;
    std::atomic<std::size_t> next{0};
    std::atomic<bool> failed{false};
    run(static_cast<unsigned>(std::min<std::size_t>(wanted, blocks)), [&](unsigned) {
      try {
        for (std::size_t first; !failed.load(std::memory_order_relaxed) && (first = next.fetch_add(block)) < count;) {
          const std::size_t last = std::min(count, first + block);
          for (std::size_t i = first; i < last; ++i) fn(i);
        }
      } catch (...) {
        failed = true;
        throw;
      }
    });
  }

 private:
  void work(unsigned id);

  std::vector<std::thread> threads_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  const std::function<void(unsigned)>* job_ = nullptr;
  unsigned joining_ = 0;      // workers 1 .. joining_ take part in the current job
  unsigned running_ = 0;      // of those, still running
  std::uint64_t generation_ = 0;
  std::exception_ptr error_;  // the first exception of the current job
  bool stopping_ = false;
  std::atomic<bool> busy_{false};
};

}  // namespace bvh_collision
