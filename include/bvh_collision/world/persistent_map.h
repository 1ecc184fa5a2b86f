// A hash map whose copies share everything they have in common (a hash array mapped trie): 32-way
// nodes indexed by five bits of the key's hash at a time, so that a change copies only the nodes
// on one path (at most 13 for a 64-bit hash, each of at most 32 entries) and every other copy
// keeps reading what it held. Copying the map copies one pointer. With persistent_vector.h it lets
// a world snapshot be changed in time that grows as log n, while readers keep the one they hold.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include "bvh_collision/world/persistent_vector.h"

namespace bvh_collision {

// A hash's bits spread over all 64 (std::hash of an integer is the integer itself: cells next to
// one another would share their low bits and one path).
inline std::uint64_t mixed_hash(std::uint64_t h) {
  h += 0x9e3779b97f4a7c15ull;
  h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  return h ^ (h >> 31);
}

template <class K, class V, class Hash = std::hash<K>>
class PersistentMap {
  static constexpr unsigned kBits = 5;
  static constexpr unsigned kHashBits = 64;

  struct Leaf {
    std::uint64_t hash;
    K key;
    V value;
  };
  struct Node;
  // One of the two is set.
  struct Slot {
    std::shared_ptr<const Node> child;
    std::shared_ptr<const Leaf> leaf;
  };
  // Below the last five bits (shift >= 64) a node lists the leaves whose hashes are equal.
  struct Node {
    std::uint32_t bitmap = 0;
    std::vector<Slot> slots;  // in the order of their bits
  };
  using NodePtr = std::shared_ptr<const Node>;

 public:
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  // The same nodes (as PersistentVector::same_as).
  bool same_as(const PersistentMap& o) const { return root_ == o.root_ && size_ == o.size_; }

  const V* find(const K& key) const {
    const std::uint64_t h = hash_of(key);
    const Node* n = root_.get();
    for (unsigned shift = 0; n != nullptr; shift += kBits) {
      if (shift >= kHashBits) {
        for (const Slot& s : n->slots) {
          if (s.leaf->key == key) return &s.leaf->value;
        }
        return nullptr;
      }
      const std::uint32_t bit = std::uint32_t(1) << ((h >> shift) & 31);
      if ((n->bitmap & bit) == 0) return nullptr;
      const Slot& s = n->slots[position(n->bitmap, bit)];
      if (s.leaf) return s.leaf->key == key ? &s.leaf->value : nullptr;
      n = s.child.get();
    }
    return nullptr;
  }

  // Adds the entry or replaces the value of the key.
  void set(const K& key, V value, PersistentWork* work = nullptr) {
    auto leaf = std::make_shared<const Leaf>(Leaf{hash_of(key), key, std::move(value)});
    bool added = false;
    root_ = insert(root_, 0, std::move(leaf), added, work);
    if (added) ++size_;
  }

  // False (and nothing changes) when the key is absent.
  bool erase(const K& key, PersistentWork* work = nullptr) {
    bool found = false;
    NodePtr next = remove(root_, 0, hash_of(key), key, found, work);
    if (!found) return false;
    root_ = std::move(next);
    --size_;
    return true;
  }

  void clear() {
    root_ = nullptr;
    size_ = 0;
  }

  // Calls f(key, value) for every entry (in no particular order).
  template <class F>
  void for_each(F&& f) const {
    if (root_) visit(*root_, f);
  }

 private:
  static std::uint64_t hash_of(const K& key) { return mixed_hash(static_cast<std::uint64_t>(Hash{}(key))); }
  static std::size_t position(std::uint32_t bitmap, std::uint32_t bit) {
    return static_cast<std::size_t>(__builtin_popcount(bitmap & (bit - 1)));
  }
  static void count(PersistentWork* work, std::size_t entries) {
    if (work == nullptr) return;
    ++work->nodes;
    work->entries += entries;
  }

  template <class F>
  static void visit(const Node& n, F& f) {
    for (const Slot& s : n.slots) {
      if (s.leaf) {
        f(s.leaf->key, s.leaf->value);
      } else {
        visit(*s.child, f);
      }
    }
  }

  // A node holding two leaves whose hashes agree below `shift`.
  static NodePtr pair(std::shared_ptr<const Leaf> a, std::shared_ptr<const Leaf> b, unsigned shift, PersistentWork* work) {
    auto n = std::make_shared<Node>();
    count(work, 2);
    if (shift >= kHashBits) {
      n->slots = {Slot{nullptr, std::move(a)}, Slot{nullptr, std::move(b)}};
      return n;
    }
    const unsigned ia = (a->hash >> shift) & 31, ib = (b->hash >> shift) & 31;
    if (ia == ib) {
      n->bitmap = std::uint32_t(1) << ia;
      n->slots.push_back(Slot{pair(std::move(a), std::move(b), shift + kBits, work), nullptr});
      return n;
    }
    n->bitmap = (std::uint32_t(1) << ia) | (std::uint32_t(1) << ib);
    if (ia < ib) {
      n->slots = {Slot{nullptr, std::move(a)}, Slot{nullptr, std::move(b)}};
    } else {
      n->slots = {Slot{nullptr, std::move(b)}, Slot{nullptr, std::move(a)}};
    }
    return n;
  }

  static NodePtr insert(const NodePtr& node, unsigned shift, std::shared_ptr<const Leaf> leaf, bool& added,
                        PersistentWork* work) {
    auto copy = node ? std::make_shared<Node>(*node) : std::make_shared<Node>();
    count(work, copy->slots.size());
    if (shift >= kHashBits) {
      for (Slot& s : copy->slots) {
        if (s.leaf->key == leaf->key) {
          s.leaf = std::move(leaf);
          return copy;
        }
      }
      copy->slots.push_back(Slot{nullptr, std::move(leaf)});
      added = true;
      return copy;
    }
    const std::uint32_t bit = std::uint32_t(1) << ((leaf->hash >> shift) & 31);
    const std::size_t at = position(copy->bitmap, bit);
    if ((copy->bitmap & bit) == 0) {
      copy->bitmap |= bit;
      copy->slots.insert(copy->slots.begin() + static_cast<std::ptrdiff_t>(at), Slot{nullptr, std::move(leaf)});
      added = true;
      return copy;
    }
    Slot& s = copy->slots[at];
    if (s.child) {
      s.child = insert(s.child, shift + kBits, std::move(leaf), added, work);
    } else if (s.leaf->key == leaf->key) {
      s.leaf = std::move(leaf);
    } else {
      s.child = pair(std::move(s.leaf), std::move(leaf), shift + kBits, work);
      s.leaf = nullptr;
      added = true;
    }
    return copy;
  }

  // The node without the key (null when nothing is left in it); `found` says whether it was there.
  static NodePtr remove(const NodePtr& node, unsigned shift, std::uint64_t hash, const K& key, bool& found,
                        PersistentWork* work) {
    if (node == nullptr) return nullptr;
    if (shift >= kHashBits) {
      for (std::size_t i = 0; i < node->slots.size(); ++i) {
        if (!(node->slots[i].leaf->key == key)) continue;
        found = true;
        if (node->slots.size() == 1) return nullptr;
        auto copy = std::make_shared<Node>(*node);
        count(work, copy->slots.size());
        copy->slots.erase(copy->slots.begin() + static_cast<std::ptrdiff_t>(i));
        return copy;
      }
      return node;
    }
    const std::uint32_t bit = std::uint32_t(1) << ((hash >> shift) & 31);
    if ((node->bitmap & bit) == 0) return node;
    const std::size_t at = position(node->bitmap, bit);
    const Slot& s = node->slots[at];
    NodePtr below;
    if (s.child) {
      below = remove(s.child, shift + kBits, hash, key, found, work);
      if (!found) return node;
    } else {
      if (!(s.leaf->key == key)) return node;
      found = true;
    }
    auto copy = std::make_shared<Node>(*node);
    count(work, copy->slots.size());
    if (below) {
      copy->slots[at].child = std::move(below);
      return copy;
    }
    copy->bitmap &= ~bit;
    copy->slots.erase(copy->slots.begin() + static_cast<std::ptrdiff_t>(at));
    if (copy->slots.empty()) return nullptr;
    return copy;
  }

  NodePtr root_;
  std::size_t size_ = 0;
};

}  // namespace bvh_collision
