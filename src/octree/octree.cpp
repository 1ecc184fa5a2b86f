#include "bvh_collision/octree/octree.h"

#include <algorithm>
#include <atomic>
#include <istream>
#include <limits>
#include <ostream>
#include <stdexcept>
#include <string>

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
  nodes_.clear();
  nodes_.shrink_to_fit();
  free_blocks_.clear();
  free_blocks_.shrink_to_fit();
  node_count_ = 0;
}

std::int32_t Octree::allocate_block() {
  if (!free_blocks_.empty()) {
    const std::int32_t first = free_blocks_.back();
    free_blocks_.pop_back();
    return first;
  }
  const auto first = static_cast<std::int32_t>(nodes_.size());
  nodes_.resize(nodes_.size() + 8);
  return first;
}

void Octree::release_block(std::int32_t first) { free_blocks_.push_back(first); }

// A pruned node (a leaf above voxel depth) about to be updated inside: eight children, each
// with the node's value, as OctoMap's expandNode.
void Octree::expand(std::int32_t node) {
  const std::int32_t block = allocate_block();
  for (int b = 0; b < 8; ++b) nodes_[block + b] = Node{nodes_[node].log_odds, -1, 0};
  nodes_[node].children = block;
  nodes_[node].mask = 0xFF;
  node_count_ += 8;
}

// Eight leaf children with one value collapse into their parent.
bool Octree::prune(std::int32_t node) {
  const Node n = nodes_[node];
  if (n.mask != 0xFF) return false;
  for (int b = 0; b < 8; ++b) {
    const Node& c = nodes_[n.children + b];
    if (c.children >= 0 || c.log_odds != nodes_[n.children].log_odds) return false;
  }
  nodes_[node] = Node{nodes_[n.children].log_odds, -1, 0};
  release_block(n.children);
  node_count_ -= 8;
  return true;
}

// An inner node holds the largest value among its existing children (OctoMap's conservative rule).
void Octree::refresh(std::int32_t node) {
  const Node n = nodes_[node];
  float largest = -std::numeric_limits<float>::max();
  for (int b = 0; b < 8; ++b) {
    if ((n.mask >> b) & 1) largest = std::max(largest, nodes_[n.children + b].log_odds);
  }
  nodes_[node].log_odds = largest;
}

void Octree::update(const OctreeKey& key, float change) {
  // OctoMap's early abort: the node holding the voxel already sits at the clamp the change pushes
  // towards, so nothing would change (and a pruned node is not expanded for nothing).
  if (const auto found = find(key)) {
    if (at_clamp(found->log_odds, change)) return;
  }
  revision_ = next_revision();
  bool created_root = false;
  if (nodes_.empty()) {
    nodes_.push_back(Node{});
    node_count_ = 1;
    created_root = true;
  }
  update_below(0, created_root, key, 0, change);
}

// OctoMap's updateNodeRecurs with eager evaluation: descend (creating or expanding), update the
// voxel, then on the way up prune each node or refresh its value. Indices, not references: the
// node vector may grow during the descent.
void Octree::update_below(std::int32_t node, bool just_created, const OctreeKey& key, int depth, float change) {
  if (depth == kOctreeDepth) {
    nodes_[node].log_odds = clamped(nodes_[node].log_odds + change);
    return;
  }
  const int b = child_bits(key, depth);
  bool created = false;
  if (!((nodes_[node].mask >> b) & 1)) {
    if (nodes_[node].children < 0 && !just_created) {
      expand(node);
    } else {
      add_child(node, b);
      created = true;
    }
  }
  update_below(nodes_[node].children + b, created, key, depth + 1, change);
  if (!prune(node)) refresh(node);
}

// A new child (log-odds 0) in slot b of a node that lacks it.
std::int32_t Octree::add_child(std::int32_t node, int b) {
  if (nodes_[node].children < 0) nodes_[node].children = allocate_block();
  nodes_[nodes_[node].children + b] = Node{};
  nodes_[node].mask = static_cast<std::uint8_t>(nodes_[node].mask | (1u << b));
  ++node_count_;
  return nodes_[node].children + b;
}

void Octree::update_sorted(const std::vector<OctreeKey>& keys, float change) {
  if (keys.empty()) return;
  revision_ = next_revision();
  bool created_root = false;
  if (nodes_.empty()) {
    nodes_.push_back(Node{});
    node_count_ = 1;
    created_root = true;
  }
  update_range(0, created_root, keys.data(), keys.data() + keys.size(), 0, change);
}

// update_below for a run of keys that all lie in `node`. Applying the updates one after another
// ends in the same tree: each voxel changes once, a node's value and pruning depend only on its
// children's final values, and OctoMap's early abort (the containing node already sits at the
// clamp) skips exactly the keys it would skip one by one, since they all see the same node.
void Octree::update_range(std::int32_t node, bool just_created, const OctreeKey* first, const OctreeKey* last,
                          int depth, float change) {
  if (depth == kOctreeDepth) {
    nodes_[node].log_odds = clamped(nodes_[node].log_odds + change);
    return;
  }
  if (nodes_[node].children < 0 && !just_created) {
    if (at_clamp(nodes_[node].log_odds, change)) return;
    expand(node);
  }
  while (first != last) {
    const int b = child_bits(*first, depth);
    const OctreeKey* end = first + 1;
    while (end != last && child_bits(*end, depth) == b) ++end;
    const bool created = !((nodes_[node].mask >> b) & 1);
    const std::int32_t child = created ? add_child(node, b) : nodes_[node].children + b;
    update_range(child, created, first, end, depth + 1, change);
    first = end;
  }
  if (!prune(node)) refresh(node);
}

std::optional<Octree::Lookup> Octree::find(const OctreeKey& key) const {
  if (nodes_.empty()) return std::nullopt;
  std::int32_t node = 0;
  std::uint64_t index = 0;
  for (int depth = 0;; ++depth) {
    const Node& n = nodes_[node];
    if (n.children < 0) return Lookup{depth, index, n.log_odds};  // a voxel or a pruned node
    const int b = child_bits(key, depth);
    if (!((n.mask >> b) & 1)) return std::nullopt;
    node = n.children + b;
    index = child_index(index, b);
  }
}

std::vector<Octree::Leaf> Octree::leaves() const {
  std::vector<Leaf> out;
  if (nodes_.empty()) return out;
  struct Item {
    std::int32_t node;
    int depth;
    OctreeKey key;
    std::uint64_t index;
  };
  std::vector<Item> stack{{0, 0, OctreeKey{}, 0}};
  while (!stack.empty()) {
    const Item item = stack.back();
    stack.pop_back();
    const Node& n = nodes_[item.node];
    if (n.children < 0) {
      out.push_back({item.key, item.depth, item.index, n.log_odds});
      continue;
    }
    for (int b = 0; b < 8; ++b) {
      if (!((n.mask >> b) & 1)) continue;
      stack.push_back({n.children + b, item.depth + 1, child_corner(item.key, item.depth, b), child_index(item.index, b)});
    }
  }
  return out;
}

}  // namespace bvh_collision

namespace bvh_collision {
namespace {

// OctoMap numbers children x = bit 0, y = bit 1, z = bit 2; the seed's b has x = bit 2, z = bit 0.
int octomap_child(int b) { return ((b >> 2) & 1) | (b & 2) | ((b & 1) << 2); }

}  // namespace

void Octree::write_nodes(std::ostream& out) const {
  if (nodes_.empty()) return;
  std::vector<std::int32_t> stack{0};
  while (!stack.empty()) {
    const Node n = nodes_[stack.back()];
    stack.pop_back();
    out.write(reinterpret_cast<const char*>(&n.log_odds), sizeof(float));
    unsigned char bits = 0;
    for (int b = 0; b < 8; ++b) {
      if ((n.mask >> b) & 1) bits = static_cast<unsigned char>(bits | (1u << octomap_child(b)));
    }
    out.write(reinterpret_cast<const char*>(&bits), 1);
    // Children in OctoMap's order, the first on top of the stack.
    for (int i = 7; i >= 0; --i) {
      const int b = octomap_child(i);  // the mapping is its own inverse
      if ((n.mask >> b) & 1) stack.push_back(n.children + b);
    }
  }
}

void Octree::read_below(std::int32_t node, int depth, std::istream& in) {
  float value = 0.0f;
  unsigned char bits = 0;
  in.read(reinterpret_cast<char*>(&value), sizeof(float));
  in.read(reinterpret_cast<char*>(&bits), 1);
  if (!in) throw std::runtime_error("octree node stream ends early (truncated file?)");
  if (!std::isfinite(value)) throw std::runtime_error("octree node stream holds a non-finite log-odds");
  if (bits != 0 && depth == kOctreeDepth) throw std::runtime_error("octree node stream is deeper than 16 levels");
  nodes_[node].log_odds = value;
  for (int i = 0; i < 8; ++i) {
    if ((bits >> i) & 1) read_below(add_child(node, octomap_child(i)), depth + 1, in);
  }
  if (nodes_[node].children >= 0) refresh(node);
}

Octree Octree::read_nodes(std::istream& in, double resolution, const OccupancyModel& model) {
  Octree tree(resolution, model);
  if (in.peek() == std::char_traits<char>::eof()) return tree;
  tree.nodes_.push_back(Node{});
  tree.node_count_ = 1;
  tree.read_below(0, 0, in);
  tree.revision_ = next_revision();
  return tree;
}

}  // namespace bvh_collision
