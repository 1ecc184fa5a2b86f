#include "bvh_collision/geometry/thread_pool.h"

#include <sys/resource.h>

#include <algorithm>
#include <cerrno>

namespace bvh_collision {
namespace {

thread_local ThreadPool* this_threads_pool = nullptr;

}  // namespace

ThreadPool::ThreadPool(unsigned workers, int nice) {
  threads_.reserve(workers);
  for (unsigned id = 1; id <= workers; ++id) {
    threads_.emplace_back([this, id, nice] {
      if (nice > 0) lower_this_thread(nice);
      work(id);
    });
  }
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& t : threads_) t.join();
}

ThreadPool& ThreadPool::shared() {
  if (this_threads_pool) return *this_threads_pool;
  static ThreadPool pool(std::max(1u, std::thread::hardware_concurrency()) - 1);
  return pool;
}

void ThreadPool::use_on_this_thread(ThreadPool* pool) { this_threads_pool = pool; }

bool ThreadPool::lower_this_thread(int nice) {
  // On Linux the nice value belongs to the thread (setpriority(2), "BUGS"): PRIO_PROCESS with
  // who 0 is the calling thread alone. Raising it back would need CAP_SYS_NICE: never done.
  errno = 0;
  const int now = getpriority(PRIO_PROCESS, 0);
  if (errno != 0) return false;
  const int wanted = std::min(19, nice);
  return wanted <= now || setpriority(PRIO_PROCESS, 0, wanted) == 0;
}

unsigned ThreadPool::run(unsigned participants, const std::function<void(unsigned)>& body) {
  const unsigned n = std::min(std::max(participants, 1u), capacity());
  if (n == 1 || busy_.exchange(true)) {  // alone, or the pool is lent out: the caller does it all
    body(0);
    return 1;
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);
    job_ = &body;
    joining_ = running_ = n - 1;
    error_ = nullptr;
    ++generation_;
  }
  wake_.notify_all();
  std::exception_ptr mine;
  try {
    body(0);
  } catch (...) {
    mine = std::current_exception();
  }
  std::exception_ptr theirs;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [this] { return running_ == 0; });
    job_ = nullptr;
    theirs = error_;
  }
  busy_ = false;
  if (mine) std::rethrow_exception(mine);
  if (theirs) std::rethrow_exception(theirs);
  return n;
}

void ThreadPool::work(unsigned id) {
  std::uint64_t seen = 0;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
    if (stopping_) return;
    seen = generation_;
    if (id > joining_) continue;
    const std::function<void(unsigned)>* job = job_;
    lock.unlock();
    std::exception_ptr error;
    try {
      (*job)(id);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error && !error_) error_ = error;
    if (--running_ == 0) done_.notify_all();
  }
}

}  // namespace bvh_collision
