// A vector whose copies share everything they have in common: a radix tree of 32-way nodes, so
// that a change copies only the nodes on one path from the root (at most log32(n) + 1 of them,
// each of at most 32 entries) and every other copy keeps reading what it held. Copying the vector
// itself copies one pointer. It is how a world snapshot that readers hold stays unchanged while
// the next one is written, at a cost per change that grows as log n instead of n.
#pragma once

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <memory>
#include <utility>
#include <vector>

namespace bvh_collision {

// What a change copied: nodes and the entries (elements or child pointers) they held. A test
// bounds the work of a change by these counts, not by time.
struct PersistentWork {
  std::size_t nodes = 0;
  std::size_t entries = 0;
};

template <class T>
class PersistentVector {
  static constexpr unsigned kBits = 5;
  static constexpr std::size_t kWidth = std::size_t(1) << kBits;
  static constexpr std::size_t kMask = kWidth - 1;

  // A leaf (shift 0) holds elements; an inner node holds children. One struct for both keeps
  // the path copy one function.
  struct Node {
    std::vector<std::shared_ptr<const Node>> children;
    std::vector<T> items;
  };
  using NodePtr = std::shared_ptr<const Node>;

 public:
  class const_iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = T;
    using difference_type = std::ptrdiff_t;
    using pointer = const T*;
    using reference = const T&;
    const_iterator() = default;
    const_iterator(const PersistentVector* v, std::size_t i) : v_(v), i_(i) {}
    reference operator*() const {
      if (leaf_ == nullptr || (i_ >> kBits) != leaf_index_) {
        leaf_ = v_->leaf_for(i_);
        leaf_index_ = i_ >> kBits;
      }
      return leaf_->items[i_ & kMask];
    }
    pointer operator->() const { return &**this; }
    const_iterator& operator++() {
      ++i_;
      return *this;
    }
    const_iterator operator++(int) {
      const_iterator old = *this;
      ++i_;
      return old;
    }
    bool operator==(const const_iterator& o) const { return i_ == o.i_; }
    bool operator!=(const const_iterator& o) const { return i_ != o.i_; }

   private:
    const PersistentVector* v_ = nullptr;
    std::size_t i_ = 0;
    // The leaf of the last element read: a walk reads each leaf once, not each path.
    mutable const Node* leaf_ = nullptr;
    mutable std::size_t leaf_index_ = 0;
  };

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T& operator[](std::size_t i) const {
    assert(i < size_);
    return leaf_for(i)->items[i & kMask];
  }
  const T& back() const { return (*this)[size_ - 1]; }
  // Do the two hold the very same nodes (one is a copy of the other, neither changed since)? Then
  // they hold the same elements; a vector alive beside a copy never has its nodes' addresses reused.
  bool same_as(const PersistentVector& o) const { return root_ == o.root_ && size_ == o.size_; }
  const_iterator begin() const { return const_iterator(this, 0); }
  const_iterator end() const { return const_iterator(this, size_); }

  void set(std::size_t i, T value, PersistentWork* work = nullptr) {
    assert(i < size_);
    root_ = assign(root_, shift_, i, std::move(value), work);
  }

  void push_back(T value, PersistentWork* work = nullptr) {
    if (root_ == nullptr) {
      auto leaf = std::make_shared<Node>();
      leaf->items.push_back(std::move(value));
      root_ = std::move(leaf);
      shift_ = 0;
      size_ = 1;
      count(work, 1);
      return;
    }
    if (size_ == (kWidth << shift_)) {  // full: a new root above it
      auto top = std::make_shared<Node>();
      top->children.push_back(root_);
      root_ = std::move(top);
      shift_ += kBits;
      count(work, 1);
    }
    root_ = append(root_, shift_, size_, std::move(value), work);
    ++size_;
  }

  void pop_back(PersistentWork* work = nullptr) {
    assert(size_ > 0);
    --size_;
    if (size_ == 0) {
      root_ = nullptr;
      shift_ = 0;
      return;
    }
    root_ = remove_last(root_, shift_, size_, work);
    // A root of one child is no longer needed.
    while (shift_ > 0 && root_->children.size() == 1) {
      root_ = root_->children[0];
      shift_ -= kBits;
    }
  }

  void clear() {
    root_ = nullptr;
    shift_ = 0;
    size_ = 0;
  }

 private:
  static void count(PersistentWork* work, std::size_t entries) {
    if (work == nullptr) return;
    ++work->nodes;
    work->entries += entries;
  }

  const Node* leaf_for(std::size_t i) const {
    const Node* n = root_.get();
    for (unsigned s = shift_; s > 0; s -= kBits) n = n->children[(i >> s) & kMask].get();
    return n;
  }

  static NodePtr assign(const NodePtr& node, unsigned shift, std::size_t i, T&& value, PersistentWork* work) {
    auto copy = std::make_shared<Node>(*node);
    count(work, copy->children.size() + copy->items.size());
    if (shift == 0) {
      copy->items[i & kMask] = std::move(value);
    } else {
      auto& child = copy->children[(i >> shift) & kMask];
      child = assign(child, shift - kBits, i, std::move(value), work);
    }
    return copy;
  }

  // Element `i` (== the size before) appended below `node`, which has room for it.
  static NodePtr append(const NodePtr& node, unsigned shift, std::size_t i, T&& value, PersistentWork* work) {
    auto copy = node ? std::make_shared<Node>(*node) : std::make_shared<Node>();
    count(work, copy->children.size() + copy->items.size());
    if (shift == 0) {
      copy->items.push_back(std::move(value));
      return copy;
    }
    const std::size_t k = (i >> shift) & kMask;
    NodePtr below = k < copy->children.size() ? copy->children[k] : nullptr;
    below = append(below, shift - kBits, i, std::move(value), work);
    if (k < copy->children.size()) {
      copy->children[k] = std::move(below);
    } else {
      copy->children.push_back(std::move(below));
    }
    return copy;
  }

  // Element `i` (== the size after) removed from below `node`; null when nothing is left there.
  static NodePtr remove_last(const NodePtr& node, unsigned shift, std::size_t i, PersistentWork* work) {
    if (shift == 0) {
      if ((i & kMask) == 0) return nullptr;  // it was the leaf's only element
      auto copy = std::make_shared<Node>(*node);
      count(work, copy->items.size());
      copy->items.pop_back();
      return copy;
    }
    const std::size_t k = (i >> shift) & kMask;
    NodePtr below = remove_last(node->children[k], shift - kBits, i, work);
    if (below == nullptr && k == 0) return nullptr;
    auto copy = std::make_shared<Node>(*node);
    count(work, copy->children.size());
    if (below == nullptr) {
      copy->children.pop_back();
    } else {
      copy->children[k] = std::move(below);
    }
    return copy;
  }

  NodePtr root_;
  unsigned shift_ = 0;  // kBits times the levels above the leaves
  std::size_t size_ = 0;
};

}  // namespace bvh_collision
