// The stack of a hierarchy traversal (BVH, BVH pair, octree, BVH against octree), and what a
// traversal's callback answers for a node it reached.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>
#include <vector>

namespace bvh_collision {

// What a traversal does with a node (or node pair) it reached.
enum class Visit : std::uint8_t {
  kSkip,   // prune it
  kEnter,  // descend into it (a leaf goes to the leaf callback)
  kStop,   // end the traversal now
};

// A stack that lives on the C++ stack for the usual depths (no allocation per query) and moves
// to the heap only when a degenerate hierarchy needs more. The local slots are raw bytes: items
// are small trivially copyable records, and value-initialising 256 of them on every query cost
// more than a shallow traversal itself.
template <class T, std::size_t N = 256>
class TraversalStack {
  static_assert(std::is_trivially_copyable_v<T>, "items are copied as bytes");

 public:
  bool empty() const { return size_ == 0; }
  void push(const T& v) {
    if (size_ < N) {
      std::memcpy(local_ + size_ * sizeof(T), &v, sizeof(T));
    } else {
      overflow_.push_back(v);
    }
    ++size_;
  }
  T pop() {
    --size_;
    if (size_ >= N) {
      const T v = overflow_.back();
      overflow_.pop_back();
      return v;
    }
    T v;
    std::memcpy(&v, local_ + size_ * sizeof(T), sizeof(T));
    return v;
  }

 private:
  alignas(T) unsigned char local_[N * sizeof(T)];
  std::vector<T> overflow_;
  std::size_t size_ = 0;
};

}  // namespace bvh_collision
