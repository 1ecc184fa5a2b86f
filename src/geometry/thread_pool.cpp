#include "bvh_collision/geometry/thread_pool.h"

#include <algorithm>

namespace bvh_collision {

ThreadPool::ThreadPool(unsigned workers) {
  threads_.reserve(workers);
  for (unsigned id = 1; id <= workers; ++id) threads_.emplace_back([this, id] { work(id); });
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
  static ThreadPool pool(std::max(1u, std::thread::hardware_concurrency()) - 1);
  return pool;
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
