// Keys and node indices of the environment octree (docs/design.md).
//
// Discretisation is OctoMap's, so that voxels agree bit for bit: depth 16, and along each axis
// key = floor(coordinate * (1 / resolution)) + 32768, computed exactly as OctoMap computes it
// (multiplying by the reciprocal, which for a coordinate on a voxel boundary can differ by one
// key from dividing). A point exactly on a splitting plane therefore belongs to the voxel on the
// plane's positive side. (The textbook's quadtree remark assigns such points to the left/lower side;
// we follow OctoMap so that both trees hold the same voxels.)
//
// Node indices are docs/design.md's: the root is 0, the children of node i are 8i + j (j = 1..8), and
// the bits of b = j - 1 give the child's side of its parent's centre, highest bit x, middle y,
// lowest z (1: positive side). At depth d (root 0) the side along an axis is bit (15 - d) of that
// axis's key, so a voxel's index follows from its key alone.
#pragma once

#include <cmath>
#include <cstdint>
#include <optional>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

constexpr int kOctreeDepth = 16;
constexpr int kOctreeKeyOffset = 32768;  // OctoMap's tree_max_val

struct OctreeKey {
  std::uint16_t k[3] = {0, 0, 0};
  std::uint16_t operator[](int i) const { return k[i]; }
  bool operator==(const OctreeKey& o) const { return k[0] == o.k[0] && k[1] == o.k[1] && k[2] == o.k[2]; }
  bool operator!=(const OctreeKey& o) const { return !(*this == o); }
  bool operator<(const OctreeKey& o) const {
    return k[0] != o.k[0] ? k[0] < o.k[0] : k[1] != o.k[1] ? k[1] < o.k[1] : k[2] < o.k[2];
  }
};

// The side of the parent's centre at `depth` (0 = the root's children), as docs/design.md's b bits.
inline int child_bits(const OctreeKey& key, int depth) {
  const int bit = kOctreeDepth - 1 - depth;
  return (((key.k[0] >> bit) & 1) << 2) | (((key.k[1] >> bit) & 1) << 1) | ((key.k[2] >> bit) & 1);
}

inline std::uint64_t child_index(std::uint64_t parent, int b) { return 8 * parent + static_cast<std::uint64_t>(b) + 1; }
inline std::uint64_t parent_index(std::uint64_t node) { return (node - 1) / 8; }
inline int bits_of_index(std::uint64_t node) { return static_cast<int>((node - 1) % 8); }

// The index (docs/design.md's numbering) of the node at `depth` (0 = root, 16 = voxel) that contains `key`.
inline std::uint64_t node_index(const OctreeKey& key, int depth) {
  std::uint64_t index = 0;
  for (int d = 0; d < depth; ++d) index = child_index(index, child_bits(key, d));
  return index;
}

// The lowest voxel of child b of the node at `depth` whose lowest voxel is `corner`.
inline OctreeKey child_corner(const OctreeKey& corner, int depth, int b) {
  const int bit = kOctreeDepth - 1 - depth;
  OctreeKey key = corner;
  key.k[0] = static_cast<std::uint16_t>(key.k[0] | (((b >> 2) & 1) << bit));
  key.k[1] = static_cast<std::uint16_t>(key.k[1] | (((b >> 1) & 1) << bit));
  key.k[2] = static_cast<std::uint16_t>(key.k[2] | ((b & 1) << bit));
  return key;
}

// Coordinate <-> key along one axis for a given resolution, as OctoMap computes them.
class OctreeGrid {
 public:
  explicit OctreeGrid(double resolution) : resolution_(resolution), factor_(1.0 / resolution) {}
  double resolution() const { return resolution_; }

  // nullopt outside the 16-bit key range (or for NaN / Inf).
  std::optional<std::uint16_t> key(double coordinate) const {
    const double scaled = std::floor(factor_ * coordinate);
    if (!(scaled >= -kOctreeKeyOffset && scaled < kOctreeKeyOffset)) return std::nullopt;
    return static_cast<std::uint16_t>(static_cast<int>(scaled) + kOctreeKeyOffset);
  }
  std::optional<OctreeKey> key(const Vec3& p) const {
    const auto x = key(p.x()), y = key(p.y()), z = key(p.z());
    if (!x || !y || !z) return std::nullopt;
    return OctreeKey{{*x, *y, *z}};
  }
  // The centre of the voxel with this key.
  double center(std::uint16_t key) const { return (double(int(key) - kOctreeKeyOffset) + 0.5) * resolution_; }
  Vec3 center(const OctreeKey& key) const { return {center(key.k[0]), center(key.k[1]), center(key.k[2])}; }

 private:
  double resolution_;
  double factor_;
};

}  // namespace bvh_collision
