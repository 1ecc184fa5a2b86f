#include "bvh_collision/octree/scan.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <thread>

#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/octree/voxel_set.h"

namespace bvh_collision {
namespace {

std::optional<OctreeKey> key_of(const OctreeGrid& grid, const ScanPoint& p) { return grid.key(Vec3(p.cast<double>())); }

// OctoMap's Vector3::norm(): float squares summed in float, square root in double.
double float_norm(const ScanPoint& v) {
  const float squared = v.x() * v.x() + v.y() * v.y() + v.z() * v.z();
  return std::sqrt(static_cast<double>(squared));
}

// OctoMap's computeRayKeys: visit(key) for every voxel a ray from `origin` to `end` crosses,
// without the end's voxel. Amanatides & Woo's traversal with OctoMap's exact mix of float and
// double arithmetic. False when either end lies outside the key range.
template <class Visit>
bool walk_ray(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, Visit&& visit) {
  const auto key_origin = key_of(grid, origin), key_end = key_of(grid, end);
  if (!key_origin || !key_end) return false;
  if (*key_origin == *key_end) return true;
  visit(*key_origin);
  ScanPoint direction = end - origin;
  const float length = static_cast<float>(float_norm(direction));
  // Ends a denormal distance apart in different voxels: the length underflows to 0 and the
  // direction to infinities and NaN, with which the walk below never ended (found by the
  // point_cloud fuzz target). Such a ray crosses no voxel between its ends.
  if (!(length > 0.0f) || !std::isfinite(length)) return true;
  direction /= length;
  if (!direction.allFinite()) return true;
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
  // Each step moves one voxel along one axis: the walk needs the keys' Manhattan distance, and
  // rounding that carries it beside the end adds a step or two. The cap makes any other rounding
  // a short ray, never an endless one.
  int steps_left = 8;
  for (int i = 0; i < 3; ++i) steps_left += std::abs(int(key_end->k[i]) - int(key_origin->k[i]));
  while (steps_left-- > 0) {
    const int dim = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    current.k[dim] = static_cast<std::uint16_t>(current.k[dim] + step[dim]);
    t_max[dim] += t_delta[dim];
    if (current == *key_end) break;
    // Rounding can carry the walk past the end voxel: stop once beyond the ray's length.
    if (std::min(std::min(t_max[0], t_max[1]), t_max[2]) > length) break;
    visit(current);
  }
  return true;
}

// What one thread gathers from its share of a scan.
struct ScanPart {
  VoxelSet free, occupied;
  ScanStats stats;
  std::vector<OctreeKey> ray;  // scratch for the workspace case
};

struct KeyBox {
  OctreeKey min, max;
  bool contains(const OctreeKey& k) const {
    for (int i = 0; i < 3; ++i) {
      if (k.k[i] < min.k[i] || k.k[i] > max.k[i]) return false;
    }
    return true;
  }
};

KeyBox key_box(const OctreeGrid& grid, const ScanWorkspace& w) {
  KeyBox box;
  for (int i = 0; i < 3; ++i) {
    box.min.k[i] = grid.key(double(w.min[i])).value_or(w.min[i] < 0 ? 0 : 0xFFFF);
    box.max.k[i] = grid.key(double(w.max[i])).value_or(w.max[i] < 0 ? 0 : 0xFFFF);
  }
  return box;
}

bool within_range(const ScanPoint& p, const ScanPoint& origin, const ScanOptions& options) {
  return options.max_range < 0.0 || float_norm(p - origin) <= options.max_range;
}

// OctoMap's bounding-box branch: points outside the box (or beyond max_range) are dropped; a kept
// ray frees its voxels from the end point back to where it leaves the box.
void cast_in_workspace(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
                       const ScanOptions& options, const KeyBox& box, ScanPart& part) {
  if (!within_range(p, origin, options) || !options.workspace->contains(p)) {
    ++part.stats.skipped_workspace;
    return;
  }
  if (const auto k = key_of(grid, p)) {
    if (mark_end) part.occupied.insert(*k);
  } else {
    ++part.stats.skipped_outside;
  }
  part.ray.clear();
  if (!walk_ray(grid, origin, p, [&](const OctreeKey& k) { part.ray.push_back(k); })) return;
  for (auto it = part.ray.rbegin(); it != part.ray.rend() && box.contains(*it); ++it) part.free.insert(*it);
}

// ScanOptions::clip_rays_to_workspace: an end inside the box and within range as OctoMap has it;
// any other ray frees the voxels it crosses inside the box, up to max_range (a box is convex: they
// are one run along the ray).
void cast_clipped(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
                  const ScanOptions& options, const KeyBox& box, ScanPart& part) {
  const bool within = within_range(p, origin, options);
  if (within && options.workspace->contains(p) && mark_end) return cast_in_workspace(grid, p, true, origin, options, box, part);
  ScanPoint end = p;
  if (!within) {
    ScanPoint direction = p - origin;
    direction /= static_cast<float>(float_norm(direction));
    end = origin + direction * static_cast<float>(options.max_range);
  }
  if (!walk_ray(grid, origin, end, [&](const OctreeKey& k) {
        if (box.contains(k)) part.free.insert(k);
      })) {
    ++part.stats.skipped_outside;
  }
}

void cast(const OctreeGrid& grid, const ScanPoint& p, bool mark_end, const ScanPoint& origin,
          const ScanOptions& options, ScanPart& part) {
  const bool within = within_range(p, origin, options);
  ScanPoint end = p;
  if (!within) {
    // OctoMap shortens the ray to max_range (float arithmetic) and clears along it only.
    ScanPoint direction = p - origin;
    direction /= static_cast<float>(float_norm(direction));
    end = origin + direction * static_cast<float>(options.max_range);
  }
  const bool ray_inside = walk_ray(grid, origin, end, [&](const OctreeKey& k) { part.free.insert(k); });
  if (!within) {
    part.stats.skipped_outside += !ray_inside;
    return;
  }
  if (const auto k = key_of(grid, p)) {
    if (mark_end) part.occupied.insert(*k);
  } else {
    ++part.stats.skipped_outside;  // the end point is outside the key range: nothing inserted
  }
}

// A scan's two lists seen as one sequence: end points that mark, then end points that only clear.
struct ScanRays {
  const std::vector<ScanPoint>& points;
  const std::vector<ScanPoint>& clear_only;
  std::size_t size() const { return points.size() + clear_only.size(); }
  bool marks(std::size_t i) const { return i < points.size(); }
  const ScanPoint& operator[](std::size_t i) const { return marks(i) ? points[i] : clear_only[i - points.size()]; }
};

void cast_all(const OctreeGrid& grid, const ScanRays& rays, std::size_t first, std::size_t last,
              const ScanPoint& origin, const ScanOptions& options, ScanPart& part) {
  std::optional<KeyBox> box;
  if (options.workspace) box = key_box(grid, *options.workspace);
  for (; first != last; ++first) {
    const ScanPoint& p = rays[first];
    if (!p.allFinite()) {
      ++part.stats.skipped_invalid;
    } else if (box && options.clip_rays_to_workspace) {
      cast_clipped(grid, p, rays.marks(first), origin, options, *box, part);
    } else if (box) {
      cast_in_workspace(grid, p, rays.marks(first), origin, options, *box, part);
    } else {
      cast(grid, p, rays.marks(first), origin, options, part);
    }
  }
}

int thread_count(const ScanOptions& options, std::size_t points) {
  const int wanted = options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency());
  // A thread pays for itself only with a few thousand rays to cast.
  return static_cast<int>(std::clamp<std::size_t>(points / 4096, 1, static_cast<std::size_t>(std::max(wanted, 1))));
}

// Cast the scan's rays on several threads, each into its own sets, then merge. Threads take
// blocks of rays as they go: a depth image's far rows have rays many times longer than its near
// rows, so fixed halves would leave one core idle half the time.
ScanPart cast_scan(const OctreeGrid& grid, const ScanRays& rays, const ScanPoint& origin, const ScanOptions& options) {
  const auto threads = static_cast<unsigned>(thread_count(options, rays.size()));
  std::vector<ScanPart> parts(threads);
  constexpr std::size_t kBlock = 2048;
  std::atomic<std::size_t> next{0};
  // Each participant gathers into its own part; whoever takes part (the caller alone when the
  // pool is busy) takes blocks until none is left.
  ThreadPool::shared().run(threads, [&](unsigned t) {
    for (std::size_t begin; (begin = next.fetch_add(kBlock)) < rays.size();) {
      cast_all(grid, rays, begin, std::min(rays.size(), begin + kBlock), origin, options, parts[t]);
    }
  });
  ScanPart& all = parts.front();
  for (std::size_t t = 1; t < parts.size(); ++t) {
    all.free.insert_all(parts[t].free);
    all.occupied.insert_all(parts[t].occupied);
    all.stats.skipped_invalid += parts[t].stats.skipped_invalid;
    all.stats.skipped_outside += parts[t].stats.skipped_outside;
    all.stats.skipped_workspace += parts[t].stats.skipped_workspace;
  }
  return std::move(all);
}

}  // namespace

bool ray_keys(const OctreeGrid& grid, const ScanPoint& origin, const ScanPoint& end, std::vector<OctreeKey>& keys) {
  keys.clear();
  return walk_ray(grid, origin, end, [&](const OctreeKey& k) { keys.push_back(k); });
}

ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const ScanPoint& origin,
                      const ScanOptions& options) {
  return insert_scan(tree, points, {}, origin, options);
}

ScanStats insert_scan(Octree& tree, const std::vector<ScanPoint>& points, const std::vector<ScanPoint>& clear_only,
                      const ScanPoint& origin, const ScanOptions& options) {
  check_limit("a scan with its points", double(points.size()) + double(clear_only.size()), options.limits.cloud_points,
              "max_cloud_points");
  if (options.max_range > 0.0) {
    check_limit("a ray of max_range " + std::to_string(options.max_range) + " m at resolution " +
                    std::to_string(tree.resolution()) + " m with its voxels",
                std::ceil(options.max_range / tree.resolution()), options.limits.ray_voxels, "max_ray_voxels");
  }
  const ScanRays rays{points, clear_only};
  ScanPart scan = cast_scan(tree.grid(), rays, origin, options);
  scan.stats.points = rays.size();
  // A voxel that ends a ray is occupied, not also freed. Free updates go first, as in OctoMap.
  scan.free.erase_all(scan.occupied);
  const std::vector<OctreeKey> free = scan.free.sorted_keys(), occupied = scan.occupied.sorted_keys();
  tree.update_sorted(free, false);
  tree.update_sorted(occupied, true);
  scan.stats.free = free.size();
  scan.stats.occupied = occupied.size();
  return scan.stats;
}

ScanStats insert_points(Octree& tree, const std::vector<ScanPoint>& points, const ScanOptions& options) {
  ScanStats stats;
  stats.points = points.size();
  VoxelSet occupied;
  for (const ScanPoint& p : points) {
    if (!p.allFinite()) {
      ++stats.skipped_invalid;
    } else if (options.workspace && !options.workspace->contains(p)) {
      ++stats.skipped_workspace;
    } else if (const auto k = key_of(tree.grid(), p)) {
      occupied.insert(*k);
    } else {
      ++stats.skipped_outside;
    }
  }
  const std::vector<OctreeKey> keys = occupied.sorted_keys();
  tree.update_sorted(keys, true);
  stats.occupied = keys.size();
  return stats;
}

bool PinholeCamera::valid() const {
  return std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) && std::isfinite(cy) && fx != 0.0 && fy != 0.0;
}

namespace {

// The least-squares line t = a * s + b through the pairs (s, t).
struct LineFit {
  double n = 0, s = 0, t = 0, ss = 0, st = 0;
  void add(double x, double y) { n += 1, s += x, t += y, ss += x * x, st += x * y; }
  bool spread() const { return n >= 2 && ss * n - s * s > 0.5; }  // at least two distinct pixel indices
  double slope() const { return (st * n - s * t) / (ss * n - s * s); }
  double intercept() const { return (t - slope() * s) / n; }
};

bool in_front(const ScanPoint& p) { return p.allFinite() && p.z() > 0.0f; }

}  // namespace

std::optional<PinholeCamera> fit_pinhole(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height) {
  if (organized.size() != width * height) return std::nullopt;
  LineFit across, down;  // x / z against the column, y / z against the row
  for (std::size_t v = 0; v < height; ++v) {
    for (std::size_t u = 0; u < width; ++u) {
      const ScanPoint& p = organized[v * width + u];
      if (!in_front(p)) continue;
      across.add(double(u), double(p.x()) / p.z());
      down.add(double(v), double(p.y()) / p.z());
    }
  }
  if (!across.spread() || !down.spread()) return std::nullopt;
  const double ax = across.slope(), bx = across.intercept(), ay = down.slope(), by = down.intercept();
  const PinholeCamera camera{1.0 / ax, 1.0 / ay, -bx / ax, -by / ay};
  if (!camera.valid() || !pinhole_agrees(organized, width, height, camera)) return std::nullopt;
  return camera;
}

bool pinhole_agrees(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height,
                    const PinholeCamera& camera) {
  if (organized.size() != width * height || !camera.valid()) return false;
  for (std::size_t v = 0; v < height; ++v) {
    for (std::size_t u = 0; u < width; ++u) {
      const ScanPoint& p = organized[v * width + u];
      if (!p.allFinite() || p.isZero()) continue;  // no return (some drivers write zeros)
      if (!in_front(p)) return false;              // a pinhole camera sees nothing behind it
      const double off_x = double(p.x()) / p.z() - (double(u) - camera.cx) / camera.fx;
      const double off_y = double(p.y()) / p.z() - (double(v) - camera.cy) / camera.fy;
      if (!(std::abs(off_x) <= 1e-3 && std::abs(off_y) <= 1e-3)) return false;
    }
  }
  return true;
}

std::vector<ScanPoint> no_return_ends(const std::vector<ScanPoint>& organized, std::size_t width, std::size_t height,
                                      const PinholeCamera& camera, double range) {
  if (organized.size() != width * height) {
    throw std::invalid_argument("no-return rays: the scan has " + std::to_string(organized.size()) + " points, not " +
                                std::to_string(width) + " x " + std::to_string(height));
  }
  if (!camera.valid()) throw std::invalid_argument("no-return rays: the camera model is not valid (fx, fy non-zero, all finite)");
  if (!(range > 0.0) || !std::isfinite(range)) throw std::invalid_argument("no-return rays: the range must be positive and finite");
  std::vector<ScanPoint> ends;
  for (std::size_t v = 0; v < height; ++v) {
    for (std::size_t u = 0; u < width; ++u) {
      if (organized[v * width + u].allFinite()) continue;
      const Eigen::Vector3d ray((double(u) - camera.cx) / camera.fx, (double(v) - camera.cy) / camera.fy, 1.0);
      const ScanPoint end = (ray.normalized() * range).cast<float>();
      if (end.allFinite()) ends.push_back(end);  // (a focal length of 1e-300 px has no direction to give)
    }
  }
  return ends;
}

}  // namespace bvh_collision
