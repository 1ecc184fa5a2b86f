#include "bvh_collision/octree/octree.h"

#include <algorithm>
#include <atomic>
#include <istream>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>
#include <unordered_set>

#include "bvh_collision/octree/cube_walk.h"

namespace bvh_collision {

Octree::Octree(double resolution, const OccupancyModel& model) : grid_(resolution), model_(model) {
  if (!(std::isfinite(resolution) && resolution > 0.0)) {
    throw std::invalid_argument("octree resolution must be a positive finite number of metres, got " +
                                std::to_string(resolution));
  }
}

std::uint64_t Octree::next_revision() {
  static std::atomic<std::uint64_t> counter{0};
  return ++counter;
}

void Octree::clear() {
  revision_ = next_revision();
  pages_.clear();
  pages_.shrink_to_fit();
  slots_ = 0;
  free_blocks_.clear();
  free_blocks_.shrink_to_fit();
  node_count_ = 0;
}

std::size_t Octree::distinct_memory_bytes(const std::vector<const Octree*>& trees) {
  std::unordered_set<const Page*> pages;
  std::size_t bytes = 0;
  for (const Octree* tree : trees) {
    for (const auto& page : tree->pages_) pages.insert(page.get());
    bytes += tree->pages_.capacity() * sizeof(std::shared_ptr<Page>) + tree->free_blocks_.capacity() * sizeof(std::int32_t);
  }
  return bytes + pages.size() * sizeof(Page);
}

Octree::Node& Octree::edit(std::int32_t node) {
  std::shared_ptr<Page>& page = pages_[node >> kPageShift];
  // use_count reads the count relaxed: the fence orders this thread's writes after the reads a
  // tree that just let go of the page made before its (releasing) decrement.
  if (page.use_count() > 1) page = std::make_shared<Page>(*page);
  std::atomic_thread_fence(std::memory_order_acquire);
  return page->slots[node & (kPageSlots - 1)];
}

// The root takes slot 0 of the first block (slots 1-7 stay unused: blocks stay page-aligned).
void Octree::create_root() {
  allocate_block();
  edit(0) = Node{};
  node_count_ = 1;
}

std::int32_t Octree::allocate_block() {
  if (!free_blocks_.empty()) {
    const std::int32_t first = free_blocks_.back();
    free_blocks_.pop_back();
    return first;
  }
  if (slots_ > std::numeric_limits<std::int32_t>::max() - kPageSlots) throw std::length_error("octree has too many nodes");
  if (slots_ == static_cast<std::int32_t>(pages_.size()) * kPageSlots) pages_.push_back(std::make_shared<Page>());
  const std::int32_t first = slots_;
  slots_ += 8;
  return first;
}

void Octree::release_block(std::int32_t first) { free_blocks_.push_back(first); }

// A pruned node (a leaf above voxel depth) about to be updated inside: eight children, each
// with the node's value, as OctoMap's expandNode.
void Octree::expand(std::int32_t node) {
  const std::int32_t block = allocate_block();
  const float value = at(node).log_odds;
  for (int b = 0; b < 8; ++b) edit(block + b) = Node{value, -1, 0};
  Node& n = edit(node);
  n.children = block;
  n.mask = 0xFF;
  node_count_ += 8;
}

// Eight leaf children with one value collapse into their parent.
bool Octree::prune(std::int32_t node) {
  const Node n = at(node);
  if (n.mask != 0xFF) return false;
  const float first = at(n.children).log_odds;
  for (int b = 0; b < 8; ++b) {
    const Node& c = at(n.children + b);
    if (c.children >= 0 || c.log_odds != first) return false;
  }
  edit(node) = Node{first, -1, 0};
  release_block(n.children);
  node_count_ -= 8;
  return true;
}

// An inner node holds the largest value among its existing children (OctoMap's conservative rule).
void Octree::refresh(std::int32_t node) {
  const Node n = at(node);
  float largest = -std::numeric_limits<float>::max();
  for (int b = 0; b < 8; ++b) {
    if ((n.mask >> b) & 1) largest = std::max(largest, at(n.children + b).log_odds);
  }
  set_value(node, largest);
}

void Octree::update(const OctreeKey& key, float change) {
  // OctoMap's early abort: the node holding the voxel already sits at the clamp the change pushes
  // towards, so nothing would change (and a pruned node is not expanded for nothing).
  if (const auto found = find(key)) {
    if (at_clamp(found->log_odds, change)) return;
  }
  revision_ = next_revision();
  const bool created_root = empty();
  if (created_root) create_root();
  update_below(0, created_root, key, 0, change);
}

// OctoMap's updateNodeRecurs with eager evaluation: descend (creating or expanding), update the
// voxel, then on the way up prune each node or refresh its value. Indices, not references: the
// node vector may grow during the descent.
void Octree::update_below(std::int32_t node, bool just_created, const OctreeKey& key, int depth, float change) {
  if (depth == kOctreeDepth) {
    set_value(node, clamped(at(node).log_odds + change));
    return;
  }
  const int b = child_bits(key, depth);
  bool created = false;
  if (!((at(node).mask >> b) & 1)) {
    if (at(node).children < 0 && !just_created) {
      expand(node);
    } else {
      add_child(node, b);
      created = true;
    }
  }
  update_below(at(node).children + b, created, key, depth + 1, change);
  if (!prune(node)) refresh(node);
}

// A new child (log-odds 0) in slot b of a node that lacks it.
std::int32_t Octree::add_child(std::int32_t node, int b) {
  if (at(node).children < 0) {
    const std::int32_t block = allocate_block();
    edit(node).children = block;
  }
  const std::int32_t slot = at(node).children + b;
  edit(slot) = Node{};
  Node& n = edit(node);
  n.mask = static_cast<std::uint8_t>(n.mask | (1u << b));
  ++node_count_;
  return slot;
}

void Octree::update_sorted(const std::vector<OctreeKey>& keys, float change, std::vector<OctreeKey>* flipped) {
  if (keys.empty()) return;
  revision_ = next_revision();
  const bool created_root = empty();
  if (created_root) create_root();
  update_range(0, created_root, keys.data(), keys.data() + keys.size(), 0, change, flipped);
}

// update_below for a run of keys that all lie in `node`. Applying the updates one after another
// ends in the same tree: each voxel changes once, a node's value and pruning depend only on its
// children's final values, and OctoMap's early abort (the containing node already sits at the
// clamp) skips exactly the keys it would skip one by one, since they all see the same node.
void Octree::update_range(std::int32_t node, bool just_created, const OctreeKey* first, const OctreeKey* last,
                          int depth, float change, std::vector<OctreeKey>* flipped) {
  if (depth == kOctreeDepth) {
    // (A voxel just created was unknown, which counts as free; an expanded one holds the value of
    // the pruned node it was part of.)
    const bool was = !just_created && occupied(at(node).log_odds);
    set_value(node, clamped(at(node).log_odds + change));
    if (flipped != nullptr && occupied(at(node).log_odds) != was) flipped->push_back(*first);
    return;
  }
  if (at(node).children < 0 && !just_created) {
    if (at_clamp(at(node).log_odds, change)) return;
    expand(node);
  }
  while (first != last) {
    const int b = child_bits(*first, depth);
    const OctreeKey* end = first + 1;
    while (end != last && child_bits(*end, depth) == b) ++end;
    const bool created = !((at(node).mask >> b) & 1);
    const std::int32_t child = created ? add_child(node, b) : at(node).children + b;
    update_range(child, created, first, end, depth + 1, change, flipped);
    first = end;
  }
  if (!prune(node)) refresh(node);
}

std::optional<Octree::Lookup> Octree::find(const OctreeKey& key) const {
  if (empty()) return std::nullopt;
  std::int32_t node = 0;
  std::uint64_t index = 0;
  for (int depth = 0;; ++depth) {
    const Node& n = at(node);
    if (n.children < 0) return Lookup{depth, index, n.log_odds};  // a voxel or a pruned node
    const int b = child_bits(key, depth);
    if (!((n.mask >> b) & 1)) return std::nullopt;
    node = n.children + b;
    index = child_index(index, b);
  }
}

std::vector<Octree::Leaf> Octree::leaves() const {
  std::vector<Leaf> out;
  for_each_leaf(*this, [&](const Leaf& leaf) { out.push_back(leaf); });
  return out;
}

}  // namespace bvh_collision

namespace bvh_collision {
namespace {

// OctoMap numbers children x = bit 0, y = bit 1, z = bit 2; docs/design.md's b has x = bit 2, z = bit 0.
int octomap_child(int b) { return ((b >> 2) & 1) | (b & 2) | ((b & 1) << 2); }

}  // namespace

void Octree::write_nodes(std::ostream& out) const {
  // Depth first, children in OctoMap's order: each node's value, then its child bits in OctoMap's numbering.
  walk_nodes(
      *this,
      [&](const OctreeCube& c) {
        const Node& n = at(c.node);
        out.write(reinterpret_cast<const char*>(&n.log_odds), sizeof(float));
        unsigned char bits = 0;
        for (int b = 0; b < 8; ++b) {
          if ((n.mask >> b) & 1) bits = static_cast<unsigned char>(bits | (1u << octomap_child(b)));
        }
        out.write(reinterpret_cast<const char*>(&bits), 1);
        return Visit::kEnter;
      },
      kOctomapChildOrder);
}

void Octree::read_below(std::int32_t node, int depth, std::istream& in) {
  float value = 0.0f;
  unsigned char bits = 0;
  in.read(reinterpret_cast<char*>(&value), sizeof(float));
  in.read(reinterpret_cast<char*>(&bits), 1);
  if (!in) throw std::runtime_error("octree node stream ends early (truncated file?)");
  if (!std::isfinite(value)) throw std::runtime_error("octree node stream holds a non-finite log-odds");
  if (bits != 0 && depth == kOctreeDepth) throw std::runtime_error("octree node stream is deeper than 16 levels");
  edit(node).log_odds = value;
  for (int i = 0; i < 8; ++i) {
    if ((bits >> i) & 1) read_below(add_child(node, octomap_child(i)), depth + 1, in);
  }
  if (at(node).children >= 0) refresh(node);
}

Octree Octree::read_nodes(std::istream& in, double resolution, const OccupancyModel& model) {
  Octree tree(resolution, model);
  if (in.peek() == std::char_traits<char>::eof()) return tree;
  tree.create_root();
  tree.read_below(0, 0, in);
  tree.revision_ = next_revision();
  return tree;
}

}  // namespace bvh_collision
