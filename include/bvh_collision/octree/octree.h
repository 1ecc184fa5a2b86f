// The environment octree: OctoMap's occupancy model on docs/design.md's node numbering (octree_key.h).
//
// Nodes live in numbered slots; an inner node owns a block of eight consecutive slots (slot b
// holds the child with seed bits b, present when bit b of `mask` is set). Only nodes that some
// update reached exist, so memory follows what was observed, not the bounding cube. Values and
// their evolution are OctoMap's, float for float: log-odds updates with clamping, new nodes at
// 0, an inner node holds the maximum of its existing children, eight equal leaf children are
// pruned into their parent, and an update inside a pruned node expands it first.
//
// The slots are stored in fixed pages shared between copies: copying a tree copies a table of
// page pointers, and a change copies only the pages it writes (copy on write). A snapshot kept
// by a reader thus costs only the pages changed since, and a one-voxel change on a map of
// millions of nodes copies a few kilobytes, not the map. A page is written in place only while
// no other tree holds it.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <optional>
#include <vector>

#include "bvh_collision/octree/octree_key.h"

namespace bvh_collision {

// OctoMap's log-odds of a probability, rounded to float as OctoMap stores it.
inline float log_odds(double probability) { return static_cast<float>(std::log(probability / (1.0 - probability))); }

// The sensor model (OctoMap's defaults), in log-odds.
struct OccupancyModel {
  float hit = log_odds(0.7);
  float miss = log_odds(0.4);
  float clamp_min = log_odds(0.1192);
  float clamp_max = log_odds(0.971);
  float occupied = log_odds(0.5);  // a node is occupied when its log-odds is >= this
};

class Octree {
 public:
  // Throws std::invalid_argument unless resolution is finite and > 0.
  explicit Octree(double resolution, const OccupancyModel& model = {});

  double resolution() const { return grid_.resolution(); }
  const OctreeGrid& grid() const { return grid_; }
  const OccupancyModel& model() const { return model_; }

  // OctoMap's updateNode: add `change` to the voxel's log-odds and clamp.
  void update(const OctreeKey& key, float change);
  void update(const OctreeKey& key, bool occupied) { update(key, occupied ? model_.hit : model_.miss); }

  // The same as update(key, change) for each key in turn, in one descent: keys must be distinct
  // and in depth-first order (VoxelSet::sorted_keys, or sorted by morton_code). `flipped`, when
  // given, gets the keys whose occupancy changed (what a distance field must follow).
  void update_sorted(const std::vector<OctreeKey>& keys, float change, std::vector<OctreeKey>* flipped = nullptr);
  void update_sorted(const std::vector<OctreeKey>& keys, bool occupied, std::vector<OctreeKey>* flipped = nullptr) {
    update_sorted(keys, occupied ? model_.hit : model_.miss, flipped);
  }

  // The smallest existing node containing the voxel: its depth (16 = voxel), seed index and
  // log-odds; nullopt when the voxel was never observed.
  struct Lookup {
    int depth = 0;
    std::uint64_t index = 0;
    float log_odds = 0.0f;
  };
  std::optional<Lookup> find(const OctreeKey& key) const;
  bool occupied(float value) const { return value >= model_.occupied; }

  // Every leaf (a node without children, possibly a pruned one above depth 16): the key of its
  // lowest corner voxel, its depth, its seed index and log-odds.
  struct Leaf {
    OctreeKey key;
    int depth = 0;
    std::uint64_t index = 0;
    float log_odds = 0.0f;
  };
  std::vector<Leaf> leaves() const;

  // Walking the tree (for queries that descend it together with another hierarchy): node ids,
  // -1 for none. A node's cube follows from the key of its lowest voxel and its depth.
  std::int32_t root() const { return empty() ? -1 : 0; }
  float value(std::int32_t node) const { return at(node).log_odds; }
  bool is_leaf(std::int32_t node) const { return at(node).children < 0; }
  // Bit b set when child b exists; child b is then node children_block(node) + b.
  std::uint8_t child_mask(std::int32_t node) const { return at(node).mask; }
  std::int32_t children_block(std::int32_t node) const { return at(node).children; }
  std::int32_t child(std::int32_t node, int b) const {
    const Node& n = at(node);
    return ((n.mask >> b) & 1) ? n.children + b : -1;
  }
  // Lowest corner and side of the cube of the node at `depth` whose lowest voxel is `corner`.
  Vec3 cube_min(const OctreeKey& corner) const {
    return Vec3(double(int(corner.k[0]) - kOctreeKeyOffset), double(int(corner.k[1]) - kOctreeKeyOffset),
                double(int(corner.k[2]) - kOctreeKeyOffset)) * grid_.resolution();
  }
  double cube_size(int depth) const { return grid_.resolution() * double(1 << (kOctreeDepth - depth)); }

  // Point, box, sphere and ray queries (octree_queries.cpp). Unknown space counts as free.
  // The smallest existing node containing p (a descent from the root, one level a step).
  std::optional<Leaf> locate(const Vec3& p) const;
  // Occupied leaves whose cubes meet the closed box [min, max] (touching counts).
  std::vector<Leaf> occupied_in_box(const Vec3& min, const Vec3& max) const;
  // Occupied leaves whose cubes meet the closed ball; `any` stops at the first.
  std::vector<Leaf> occupied_in_sphere(const Vec3& centre, double radius, bool any = false) const;
  // The first occupied cube along origin + s * direction / |direction|, 0 <= s <= max_range.
  struct RayHit {
    Leaf leaf;
    double distance = 0.0;  // 0 when the origin lies in occupied space
    Vec3 point = Vec3::Zero();
  };
  std::optional<RayHit> cast_ray(const Vec3& origin, const Vec3& direction, double max_range) const;
  // Forget every voxel whose key lies between the keys of min and max (they become unknown).
  void clear_box(const Vec3& min, const Vec3& max);

  // The node stream of OctoMap's .ot data section (OcTreeBaseImpl::writeData / readData): depth
  // first, each node's float log-odds, then a byte with a bit per existing child in OctoMap's
  // child order (bit 0 x, bit 1 y, bit 2 z). read_nodes throws std::runtime_error on a truncated
  // or malformed stream; inner values are recomputed as the maximum of their children.
  void write_nodes(std::ostream& out) const;
  static Octree read_nodes(std::istream& in, double resolution, const OccupancyModel& model = {});

  bool empty() const { return slots_ == 0; }
  // Changes with every update, clear and read, and is never reused by any tree of the process:
  // two trees (a tree and its copy) with the same revision hold the same voxels, so what is
  // computed from a tree (a distance field) can be kept with its revision.
  std::uint64_t revision() const { return revision_; }
  std::size_t node_count() const { return node_count_; }
  // What this tree holds, counting pages it shares with other trees in full.
  std::size_t memory_bytes() const { return distinct_memory_bytes({this}); }
  // What the trees hold together, each shared page counted once: the memory of a set of
  // snapshots of one map.
  static std::size_t distinct_memory_bytes(const std::vector<const Octree*>& trees);
  void clear();

 private:
  struct Node {
    float log_odds = 0.0f;
    std::int32_t children = -1;  // first slot of the children's block; -1: leaf
    std::uint8_t mask = 0;       // which of the eight slots hold a child
  };

  // Slot storage: 2^kPageShift slots a page (6 KiB); blocks of eight never straddle a page.
  static constexpr int kPageShift = 9;
  static constexpr std::int32_t kPageSlots = std::int32_t(1) << kPageShift;
  struct Page {
    Node slots[kPageSlots];
  };
  const Node& at(std::int32_t node) const { return pages_[node >> kPageShift]->slots[node & (kPageSlots - 1)]; }
  // The slot for writing: its page is copied first when another tree shares it. The reference
  // is valid until the next call to edit (which may copy the page it points into).
  Node& edit(std::int32_t node);
  void set_value(std::int32_t node, float value) {
    if (at(node).log_odds != value) edit(node).log_odds = value;  // an unchanged page stays shared
  }
  void create_root();

  std::int32_t allocate_block();
  void release_block(std::int32_t first);
  void expand(std::int32_t node);
  bool prune(std::int32_t node);
  void refresh(std::int32_t node);
  void update_below(std::int32_t node, bool just_created, const OctreeKey& key, int depth, float change);
  void update_range(std::int32_t node, bool just_created, const OctreeKey* first, const OctreeKey* last, int depth,
                    float change, std::vector<OctreeKey>* flipped);
  bool at_clamp(float value, float change) const {
    return (change >= 0 && value >= model_.clamp_max) || (change <= 0 && value <= model_.clamp_min);
  }
  float clamped(float value) const { return std::min(std::max(value, model_.clamp_min), model_.clamp_max); }
  std::int32_t add_child(std::int32_t node, int b);
  bool clear_below(std::int32_t node, const OctreeKey& corner, int depth, const OctreeKey& lo, const OctreeKey& hi);
  void release_below(std::int32_t node);
  void read_below(std::int32_t node, int depth, std::istream& in);

  OctreeGrid grid_;
  OccupancyModel model_;
  std::vector<std::shared_ptr<Page>> pages_;  // slot 0 is the root once anything was observed
  std::int32_t slots_ = 0;                      // slots in use or released: a multiple of 8
  std::vector<std::int32_t> free_blocks_;  // released blocks, reused first
  std::size_t node_count_ = 0;
  std::uint64_t revision_ = next_revision();
  static std::uint64_t next_revision();
};

}  // namespace bvh_collision
