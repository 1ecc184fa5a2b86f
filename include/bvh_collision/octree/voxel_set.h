// A set of voxel keys, built for the millions of voxels the rays of one scan cross.
//
// Keys are grouped in blocks of 8x8x8 voxels, one 512-bit bitmap per block, found through an
// open-addressing hash table. Consecutive voxels of a ray mostly share a block, so marking one
// costs a compare and a bit-or; the alternative, sorting every crossed key (tens of millions at
// 2 cm), dominated insertion. Inside a block the bit index is the voxels' Morton order, and blocks
// are listed in Morton order, so `sorted_keys` yields keys in the octree's depth-first order.
#pragma once

#include <cstdint>
#include <vector>

#include "bvh_collision/octree/octree_key.h"

namespace bvh_collision {

class VoxelSet {
 public:
  void insert(const OctreeKey& key) {
    const std::uint64_t id = block_id(key);
    if (id != last_id_) {
      last_block_ = find_or_add(id);
      last_id_ = id;
    }
    const unsigned bit = local_bit(key);
    blocks_[last_block_].bits[bit >> 6] |= std::uint64_t{1} << (bit & 63);
  }
  bool contains(const OctreeKey& key) const;
  void insert_all(const VoxelSet& other);  // union
  void erase_all(const VoxelSet& other);   // difference
  std::size_t size() const;
  bool empty() const { return size() == 0; }
  void clear();

  // Every key once, in the octree's depth-first (Morton) order, highest bit x, then y, then z.
  std::vector<OctreeKey> sorted_keys() const;

 private:
  struct Block {
    std::uint64_t id = 0;
    std::uint64_t bits[8] = {0, 0, 0, 0, 0, 0, 0, 0};
  };
  static std::uint64_t block_id(const OctreeKey& k) {
    return (std::uint64_t(k.k[0] >> 3) << 26) | (std::uint64_t(k.k[1] >> 3) << 13) | (k.k[2] >> 3);
  }
  // Morton index of the key's voxel inside its block: bits x2 y2 z2 x1 y1 z1 x0 y0 z0.
  static unsigned local_bit(const OctreeKey& k) {
    static constexpr unsigned spread[8] = {0b000, 0b001, 0b1000, 0b1001, 0b1000000, 0b1000001, 0b1001000, 0b1001001};
    return (spread[k.k[0] & 7] << 2) | (spread[k.k[1] & 7] << 1) | spread[k.k[2] & 7];
  }
  std::uint32_t find_or_add(std::uint64_t id);
  std::int64_t find(std::uint64_t id) const;
  void grow();

  std::vector<Block> blocks_;
  std::vector<std::uint32_t> slots_;  // 0: empty, else 1 + index into blocks_
  std::uint64_t last_id_ = ~std::uint64_t{0};
  std::uint32_t last_block_ = 0;
};

// A set of voxel keys inside one box of keys, one bit a voxel: where every voxel a scan's rays
// cross lies in a small box (a room's depth image at 5 cm: 113 x 94 x 62 voxels, 82 KB), marking a
// crossed voxel costs an index and a bit-or, where VoxelSet pays a block's hash lookup whenever a
// ray enters another block. A key outside the box is not taken (insert says so).
class VoxelBitGrid {
 public:
  VoxelBitGrid() = default;
  VoxelBitGrid(const OctreeKey& min, const OctreeKey& max);  // the box, both corners included
  // Voxels in the box from min to max (0 when a max is below its min).
  static std::uint64_t volume(const OctreeKey& min, const OctreeKey& max);

  // Marks voxel (x, y, z) (16-bit keys as ints); false, marking nothing, outside the box.
  bool insert(int x, int y, int z) {
    std::uint64_t i = 0;
    if (!index_of(x, y, z, i)) return false;
    mark(i);
    return true;
  }
  bool contains(const OctreeKey& key) const;
  bool has_box() const { return !words_.empty(); }

  // For a walk that follows its voxel by index: the box (keys as ints), a step's change of the
  // index along each axis, the bit of voxel (x, y, z) (false outside the box), marking by index.
  int min(int axis) const { return min_[axis]; }
  int max(int axis) const { return min_[axis] + static_cast<int>(size_[axis]) - 1; }
  std::uint64_t stride(int axis) const { return axis == 0 ? stride_x_ : axis == 1 ? stride_y_ : 1; }
  bool index_of(int x, int y, int z, std::uint64_t& index) const {
    const auto ux = static_cast<unsigned>(x - min_[0]), uy = static_cast<unsigned>(y - min_[1]), uz = static_cast<unsigned>(z - min_[2]);
    if ((ux >= size_[0]) | (uy >= size_[1]) | (uz >= size_[2])) return false;
    index = ux * stride_x_ + uy * stride_y_ + uz;
    return true;
  }
  void mark(std::uint64_t index) { words_[index >> 6] |= std::uint64_t{1} << (index & 63); }
  std::uint64_t* words() { return words_.data(); }
  void insert_all(const VoxelBitGrid& other);  // union; the same box
  void append_to(VoxelSet& set) const;         // every key of this set into `set`
  std::size_t size() const;

 private:
  int min_[3] = {0, 0, 0};
  unsigned size_[3] = {0, 0, 0};
  std::uint64_t stride_x_ = 0, stride_y_ = 0;
  std::vector<std::uint64_t> words_;
};

// The octree's depth-first order as one integer: the keys' bits interleaved, x highest.
std::uint64_t morton_code(const OctreeKey& key);

}  // namespace bvh_collision
