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

// The octree's depth-first order as one integer: the keys' bits interleaved, x highest.
std::uint64_t morton_code(const OctreeKey& key);

}  // namespace bvh_collision
