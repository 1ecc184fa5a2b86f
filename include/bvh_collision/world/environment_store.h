// Concurrent access to the environment: many readers (queries) and one writer at a time (scan
// insertion, clear_box, objects). Readers take an immutable snapshot, so a query never sees a
// half-updated octree and never waits for an insertion; a writer changes its own working copy
// and then publishes a fresh snapshot of it.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <type_traits>
#include <utility>

#include "bvh_collision/world/environment.h"

namespace bvh_collision {

class EnvironmentStore {
 public:
  explicit EnvironmentStore(Environment initial)
      : working_(std::move(initial)), current_(std::make_shared<const Environment>(working_)) {}

  // The latest published environment; it stays valid (and unchanged) while the caller holds it.
  std::shared_ptr<const Environment> snapshot() const {
    std::lock_guard<std::mutex> lock(pointer_mutex_);
    return current_;
  }

  // Publications so far: a reader can tell whether anything changed since it last looked.
  std::uint64_t version() const {
    std::lock_guard<std::mutex> lock(pointer_mutex_);
    return version_;
  }

  // Applies `change(Environment&)` to the working copy and publishes the result. When `change`
  // throws, the working copy goes back to the last snapshot and nothing is published: a bad
  // request loses nothing. Writers run one at a time; readers are never blocked by them beyond
  // the swap of a pointer. Returns what `change` returns.
  template <class Change>
  auto modify(Change&& change) {
    std::lock_guard<std::mutex> write(write_mutex_);
    try {
      if constexpr (std::is_void_v<decltype(change(working_))>) {
        change(working_);
        publish();
      } else {
        auto result = change(working_);
        publish();
        return result;
      }
    } catch (...) {
      working_ = *snapshot();
      throw;
    }
  }

 private:
  void publish() {
    // The copy is made outside the pointer lock: readers only ever wait for the swap.
    auto next = std::make_shared<const Environment>(working_);
    std::lock_guard<std::mutex> lock(pointer_mutex_);
    current_.swap(next);
    ++version_;
  }

  std::mutex write_mutex_;  // one writer at a time; guards working_
  Environment working_;
  mutable std::mutex pointer_mutex_;  // guards current_ and version_
  std::shared_ptr<const Environment> current_;
  std::uint64_t version_ = 0;
};

}  // namespace bvh_collision
