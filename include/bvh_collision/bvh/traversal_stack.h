// The stack of a hierarchy traversal (BVH against BVH, BVH against octree).
#pragma once

#include <array>
#include <cstddef>
#include <vector>

namespace bvh_collision {

// A stack that lives on the C++ stack for the usual depths (no allocation per query) and moves
// to the heap only when a degenerate hierarchy needs more.
template <class T, std::size_t N = 256>
class TraversalStack {
 public:
  bool empty() const { return size_ == 0; }
  void push(const T& v) {
    if (size_ < N) {
      local_[size_++] = v;
    } else {
      overflow_.push_back(v);
      ++size_;
    }
  }
  T pop() {
    --size_;
    if (size_ >= N) {
      const T v = overflow_.back();
      overflow_.pop_back();
      return v;
    }
    return local_[size_];
  }

 private:
  std::array<T, N> local_;
  std::vector<T> overflow_;
  std::size_t size_ = 0;
};

}  // namespace bvh_collision
