#include "bvh_collision/octree/scan.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace bvh_collision {
namespace {

std::optional<OctreeKey> key_of(const OctreeGrid& grid, const ScanPoint& p) { return grid.key(Vec3(p.cast<double>())); }

// OctoMap's Vector3::norm(): float squares summed in float, square root in double.
double float_norm(const ScanPoint& v) {
  const float squared = v.x() * v.x() + v.y() * v.y() + v.z() * v.z();
  return std::sqrt(static_cast<double>(squared));
}

std::uint64_t packed(const OctreeKey& k) {
  return (std::uint64_t{k.k[0]} << 32) | (std::uint64_t{k.k[1]} << 16) | k.k[2];
}

OctreeKey unpacked(std::uint64_t v) {
  return OctreeKey{{static_cast<std::uint16_t>(v >> 32), static_cast<std::uint16_t>(v >> 16), static_cast<std::uint16_t>(v)}};
}

void sort_unique(std::vector<std::uint64_t>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

}  // namespace

bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys) {
  keys.clear();
  const auto key_origin = key_of(grid, origin), key_end = key_of(grid, end);
  if (!key_origin || !key_end) return false;
  if (*key_origin == *key_end) return true;
  keys.push_back(*key_origin);
  // Amanatides & Woo's traversal with OctoMap's exact mix of float and double arithmetic.
  ScanPoint direction = end - origin;
  const float length = static_cast<float>(float_norm(direction));
  direction /= length;
  int step[3];
  double t_max[3], t_delta[3];
  OctreeKey current = *key_origin;
  for (int i = 0; i < 3; ++i) {
    step[i] = direction[i] > 0.0f ? 1 : (direction[i] < 0.0f ? -1 : 0);
    if (step[i] == 0) {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::max();
      continue;
    }
    double border = grid.center(current.k[i]);
    border += static_cast<float>(step[i] * grid.resolution() * 0.5);
    t_max[i] = (border - origin[i]) / direction[i];
    t_delta[i] = grid.resolution() / std::fabs(direction[i]);
  }
  while (true) {
    const int dim = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    current.k[dim] = static_cast<std::uint16_t>(current.k[dim] + step[dim]);
    t_max[dim] += t_delta[dim];
    if (current == *key_end) break;
    // Rounding can carry the walk past the end voxel: stop once beyond the ray's length.
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length) break;
    keys.push_back(current);
  }
  return true;
}

ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const ScanPoint& origin,
                      const ScanOptions& options) {
  ScanStats stats;
  stats.points = points.size();
  const OctreeGrid& grid = tree.grid();
  std::vector<std::uint64_t> free, occupied;
  std::vector<OctreeKey> ray;
  for (const ScanPoint& p : points) {
    if (!p.allFinite()) {
      ++stats.skipped_invalid;
      continue;
    }
    ScanPoint end = p;
    const bool within = options.max_range < 0.0 || float_norm(p - origin) <= options.max_range;
    if (!within) {
      // OctoMap shortens the ray to max_range (float arithmetic) and clears along it only.
      ScanPoint direction = p - origin;
      direction /= static_cast<float>(float_norm(direction));
      end = origin + direction * static_cast<float>(options.max_range);
    }
    const bool ray_inside = ray_keys(grid, origin, end, ray);
    if (ray_inside) {
      for (const OctreeKey& k : ray) free.push_back(packed(k));
    }
    if (!within) {
      stats.skipped_outside += !ray_inside;
      continue;
    }
    if (const auto k = key_of(grid, p)) {
      occupied.push_back(packed(*k));
    } else {
      ++stats.skipped_outside;  // the end point is outside the key range: nothing inserted
    }
  }
  sort_unique(free);
  sort_unique(occupied);
  // A voxel that ends a ray is occupied, not also freed.
  std::vector<std::uint64_t> only_free;
  std::set_difference(free.begin(), free.end(), occupied.begin(), occupied.end(), std::back_inserter(only_free));
  for (const std::uint64_t k : only_free) tree.update(unpacked(k), false);
  for (const std::uint64_t k : occupied) tree.update(unpacked(k), true);
  stats.free = only_free.size();
  stats.occupied = occupied.size();
  return stats;
}

}  // namespace bvh_collision
