// Concurrent access to the environment: many readers (queries) and one writer at a time (scan
// insertion, clear_box, objects). Readers take an immutable snapshot, so a query never sees a
// half-updated octree and never waits for an insertion; a writer changes its own working copy
// and then publishes a fresh snapshot of it.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
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

  // The world version: a reader can tell whether anything changed since it last looked. The
  // initial snapshot is world version 1, the one the n-th publication made n + 1 (0 names none: a
  // request that names no version asks the latest).
  std::uint64_t version() const {
    std::lock_guard<std::mutex> lock(pointer_mutex_);
    return version_;
  }

  // ---- Pinned versions: one world for one plan ----
  // A client that checks the states and motions of one plan against one world pins the current
  // version and names it in each query; the store keeps that snapshot (sharing every octree page
  // and object that did not change since) until it is released or `timeout` passes without a use.
  // Times are given, not read, so that callers (and tests) own the clock.
  using Clock = std::chrono::steady_clock;
  struct Pin {
    std::uint64_t version = 0;
    std::shared_ptr<const Environment> snapshot;
  };
  Pin pin(Clock::duration timeout, Clock::time_point now);
  // The latest snapshot and its version, read together.
  Pin latest() const {
    std::lock_guard<std::mutex> lock(pointer_mutex_);
    return {version_, current_};
  }
  // The pinned snapshot of `version`, its expiry renewed; throws PinError (naming `parameter`, the
  // setting that bounds a pin's life) for a version never pinned, released or expired.
  std::shared_ptr<const Environment> pinned(std::uint64_t version, Clock::time_point now,
                                            const std::string& parameter = "pin_timeout");
  // False when the version was not pinned (or had expired).
  bool release(std::uint64_t version);
  // Pins held (expired ones dropped at `now`), and the memory they hold beyond the current
  // snapshot: the octree pages and the distance field pages they do not share with it (copy on
  // write both: what changed since; a field built anew since, not updated, is a whole grid).
  std::size_t pins(Clock::time_point now);
  std::size_t pinned_extra_bytes() const;

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
  std::uint64_t version_ = 1;
  struct Held {
    std::shared_ptr<const Environment> snapshot;
    Clock::duration timeout;
    Clock::time_point expires;
  };
  mutable std::mutex pins_mutex_;  // guards pins_ (taken before pointer_mutex_, never after)
  std::map<std::uint64_t, Held> pins_;
  void drop_expired(Clock::time_point now);
};

// A query named a world version that is not (or no longer) pinned.
struct PinError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace bvh_collision
