#include "bvh_collision/octree/voxel_set.h"

#include <algorithm>

namespace bvh_collision {
namespace {

// Spread the low 16 bits of v so that bit i lands at bit 3i.
std::uint64_t spread_bits(std::uint64_t v) {
  v &= 0xFFFF;
  v = (v | (v << 16)) & 0x0000FF0000FFull;
  v = (v | (v << 8)) & 0x00F00F00F00Full;
  v = (v | (v << 4)) & 0x0C30C30C30C3ull;
  v = (v | (v << 2)) & 0x249249249249ull;
  return v;
}

// The lowest voxel of a block (inverse of VoxelSet::block_id).
OctreeKey block_corner(std::uint64_t id) {
  return OctreeKey{{static_cast<std::uint16_t>((id >> 26) << 3), static_cast<std::uint16_t>(((id >> 13) & 0x1FFF) << 3),
                    static_cast<std::uint16_t>((id & 0x1FFF) << 3)}};
}

std::uint64_t slot_of(std::uint64_t id, std::size_t mask) { return (id * 0x9E3779B97F4A7C15ull >> 20) & mask; }

}  // namespace

std::uint64_t morton_code(const OctreeKey& key) {
  return (spread_bits(key.k[0]) << 2) | (spread_bits(key.k[1]) << 1) | spread_bits(key.k[2]);
}

std::int64_t VoxelSet::find(std::uint64_t id) const {
  if (slots_.empty()) return -1;
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t s = slot_of(id, mask);; s = (s + 1) & mask) {
    if (slots_[s] == 0) return -1;
    if (blocks_[slots_[s] - 1].id == id) return slots_[s] - 1;
  }
}

std::uint32_t VoxelSet::find_or_add(std::uint64_t id) {
  if (2 * (blocks_.size() + 1) > slots_.size()) grow();
  const std::size_t mask = slots_.size() - 1;
  std::size_t s = slot_of(id, mask);
  for (; slots_[s] != 0; s = (s + 1) & mask) {
    if (blocks_[slots_[s] - 1].id == id) return slots_[s] - 1;
  }
  blocks_.push_back(Block{id, {}});
  slots_[s] = static_cast<std::uint32_t>(blocks_.size());
  return static_cast<std::uint32_t>(blocks_.size() - 1);
}

// Keep the table at most half full, so probes stay short.
void VoxelSet::grow() {
  slots_.assign(std::max<std::size_t>(1024, 2 * slots_.size()), 0);
  const std::size_t mask = slots_.size() - 1;
  for (std::size_t b = 0; b < blocks_.size(); ++b) {
    std::size_t s = slot_of(blocks_[b].id, mask);
    while (slots_[s] != 0) s = (s + 1) & mask;
    slots_[s] = static_cast<std::uint32_t>(b + 1);
  }
}

bool VoxelSet::contains(const OctreeKey& key) const {
  const std::int64_t b = find(block_id(key));
  if (b < 0) return false;
  const unsigned bit = local_bit(key);
  return (blocks_[b].bits[bit >> 6] >> (bit & 63)) & 1;
}

void VoxelSet::insert_all(const VoxelSet& other) {
  for (const Block& block : other.blocks_) {
    Block& mine = blocks_[find_or_add(block.id)];
    for (int w = 0; w < 8; ++w) mine.bits[w] |= block.bits[w];
  }
  last_id_ = ~std::uint64_t{0};
}

void VoxelSet::erase_all(const VoxelSet& other) {
  for (Block& block : blocks_) {
    const std::int64_t b = other.find(block.id);
    if (b < 0) continue;
    for (int w = 0; w < 8; ++w) block.bits[w] &= ~other.blocks_[b].bits[w];
  }
}

std::size_t VoxelSet::size() const {
  std::size_t n = 0;
  for (const Block& block : blocks_) {
    for (const std::uint64_t w : block.bits) n += static_cast<std::size_t>(__builtin_popcountll(w));
  }
  return n;
}

void VoxelSet::clear() {
  blocks_.clear();
  slots_.clear();
  last_id_ = ~std::uint64_t{0};
}

std::vector<OctreeKey> VoxelSet::sorted_keys() const {
  // Blocks in Morton order of their corner voxel; within a block the bit order is Morton order.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> order;
  order.reserve(blocks_.size());
  for (std::uint32_t b = 0; b < blocks_.size(); ++b) {
    order.emplace_back(morton_code(block_corner(blocks_[b].id)), b);
  }
  std::sort(order.begin(), order.end());
  std::vector<OctreeKey> keys;
  keys.reserve(size());
  for (const auto& [code, b] : order) {
    const Block& block = blocks_[b];
    const OctreeKey corner = block_corner(block.id);
    for (unsigned w = 0; w < 8; ++w) {
      for (std::uint64_t bits = block.bits[w]; bits != 0; bits &= bits - 1) {
        const unsigned bit = w * 64 + static_cast<unsigned>(__builtin_ctzll(bits));
        // Undo local_bit: bit 3i+2 is x's bit i, 3i+1 y's, 3i z's.
        OctreeKey k = corner;
        for (unsigned i = 0; i < 3; ++i) {
          k.k[0] = static_cast<std::uint16_t>(k.k[0] | (((bit >> (3 * i + 2)) & 1) << i));
          k.k[1] = static_cast<std::uint16_t>(k.k[1] | (((bit >> (3 * i + 1)) & 1) << i));
          k.k[2] = static_cast<std::uint16_t>(k.k[2] | (((bit >> (3 * i)) & 1) << i));
        }
        keys.push_back(k);
      }
    }
  }
  return keys;
}

VoxelBitGrid::VoxelBitGrid(const OctreeKey& min, const OctreeKey& max) {
  for (int i = 0; i < 3; ++i) {
    min_[i] = min.k[i];
    size_[i] = max.k[i] >= min.k[i] ? static_cast<unsigned>(max.k[i] - min.k[i] + 1) : 0u;
  }
  stride_y_ = size_[2];
  stride_x_ = std::uint64_t{size_[1]} * size_[2];
  words_.assign((volume(min, max) + 63) / 64, 0);
}

std::uint64_t VoxelBitGrid::volume(const OctreeKey& min, const OctreeKey& max) {
  std::uint64_t v = 1;
  for (int i = 0; i < 3; ++i) v *= max.k[i] >= min.k[i] ? std::uint64_t(max.k[i] - min.k[i] + 1) : 0;
  return v;
}

bool VoxelBitGrid::contains(const OctreeKey& key) const {
  const auto ux = static_cast<unsigned>(key.k[0] - min_[0]), uy = static_cast<unsigned>(key.k[1] - min_[1]),
             uz = static_cast<unsigned>(key.k[2] - min_[2]);
  if (ux >= size_[0] || uy >= size_[1] || uz >= size_[2]) return false;
  const std::uint64_t i = ux * stride_x_ + uy * stride_y_ + uz;
  return (words_[i >> 6] >> (i & 63)) & 1;
}

void VoxelBitGrid::insert_all(const VoxelBitGrid& other) {
  for (std::size_t w = 0; w < words_.size(); ++w) words_[w] |= other.words_[w];
}

std::size_t VoxelBitGrid::size() const {
  std::size_t n = 0;
  for (const std::uint64_t w : words_) n += static_cast<std::size_t>(__builtin_popcountll(w));
  return n;
}

// Row by row (x, then y): a row's voxels are consecutive bits, and consecutive keys of a row
// mostly share the set's block.
void VoxelBitGrid::append_to(VoxelSet& set) const {
  for (unsigned x = 0; x < size_[0]; ++x) {
    for (unsigned y = 0; y < size_[1]; ++y) {
      const std::uint64_t first = x * stride_x_ + y * stride_y_, end = first + size_[2];
      for (std::uint64_t w = first >> 6; w <= (end - 1) >> 6 && end > first; ++w) {
        std::uint64_t bits = words_[w];
        if (w == first >> 6) bits &= ~std::uint64_t{0} << (first & 63);
        if (w == (end - 1) >> 6 && (end & 63) != 0) bits &= ~(~std::uint64_t{0} << (end & 63));
        for (; bits != 0; bits &= bits - 1) {
          const std::uint64_t z = w * 64 + static_cast<unsigned>(__builtin_ctzll(bits)) - first;
          set.insert(OctreeKey{{static_cast<std::uint16_t>(min_[0] + static_cast<int>(x)), static_cast<std::uint16_t>(min_[1] + static_cast<int>(y)),
                                static_cast<std::uint16_t>(min_[2] + static_cast<int>(z))}});
        }
      }
    }
  }
}

}  // namespace bvh_collision
