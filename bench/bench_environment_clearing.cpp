// Environment benchmark, its third unit: how long an obstacle that left stays in the map, and what
// faster clearing costs (table `clearing`; environment_bench.h; main is in bench_environment.cpp).
//
// A depth camera (pinhole, 10 Hz) looks along +x at a box in front of a wall. The box is seen for
// N scans and taken away; the table counts the scans until none of its voxels reads occupied,
// for OctoMap's default sensor model and two faster ones. The price of clearing faster is paid
// by obstacles the sensor sees badly: a pole thinner than a voxel seen by a moving camera (most
// rays through its voxel pass beside it), and a dark box that returns 5 % of its pixels (the rest
// are NaN, which clear along their ray under ~clear_no_return). Their columns count how often
// one of their voxels reads free.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "bench_util.h"
#include "environment_bench.h"
#include "bvh_collision/octree/octree.h"
#include "bvh_collision/octree/scan.h"

namespace bvh_collision::environment_bench {
namespace {

using bench::Table;

struct Slab {
  Vec3 lo, hi;
  double returns = 1.0;  // the chance that a pixel on it returns (a dark surface: less)
};

// Where a ray from `o` along `d` enters the box, or infinity.
double entry(const Vec3& o, const Vec3& d, const Slab& b) {
  double a = 0.0, z = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (o[i] < b.lo[i] || o[i] > b.hi[i]) return std::numeric_limits<double>::infinity();
      continue;
    }
    const double t1 = (b.lo[i] - o[i]) / d[i], t2 = (b.hi[i] - o[i]) / d[i];
    a = std::max(a, std::min(t1, t2));
    z = std::min(z, std::max(t1, t2));
  }
  return a <= z ? a : std::numeric_limits<double>::infinity();
}

// One depth image: the camera at `origin` looking along +x (optical z), each pixel's ray to the
// nearest box or the wall (x = wall_x; none when wall_x is infinite). `world` gets the points that
// returned (world frame); `optical` the organized cloud in the camera's frame, NaN where nothing
// returned (for the no-return rays).
struct Camera {
  int width, height;
  PinholeCamera model;
  Mat3 R;  // optical -> world: z forward along +x, x right (-y), y down (-z)
};

void image(const Camera& cam, const Vec3& origin, const std::vector<Slab>& boxes, double wall_x, std::mt19937_64& rng,
           std::vector<ScanPoint>& world, std::vector<ScanPoint>& optical) {
  world.clear();
  optical.clear();
  std::uniform_real_distribution<double> chance(0.0, 1.0);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3 ray((u - cam.model.cx) / cam.model.fx, (v - cam.model.cy) / cam.model.fy, 1.0);
      const Vec3 d = cam.R * ray;
      double depth = std::isfinite(wall_x) ? (wall_x - origin.x()) / d.x() : std::numeric_limits<double>::infinity();
      double returns = 1.0;
      for (const Slab& b : boxes) {
        const double t = entry(origin, d, b);
        if (t < depth) depth = t, returns = b.returns;
      }
      if (!std::isfinite(depth) || (returns < 1.0 && chance(rng) >= returns)) {
        optical.emplace_back(nan, nan, nan);
        continue;
      }
      optical.push_back((ray * depth).cast<float>());
      world.push_back((origin + d * depth).cast<float>());
    }
  }
}

// The occupied voxels among those whose centre lies in [lo, hi].
int occupied_in(const Octree& tree, const Vec3& lo, const Vec3& hi) {
  const OctreeKey a = *tree.grid().key(lo), b = *tree.grid().key(hi);
  int n = 0;
  for (int x = a.k[0]; x <= b.k[0]; ++x) {
    for (int y = a.k[1]; y <= b.k[1]; ++y) {
      for (int z = a.k[2]; z <= b.k[2]; ++z) {
        const auto found = tree.find(OctreeKey{{std::uint16_t(x), std::uint16_t(y), std::uint16_t(z)}});
        n += found && tree.occupied(found->log_odds);
      }
    }
  }
  return n;
}

struct Model {
  std::string name;
  double hit, miss, min, max;
  OccupancyModel occupancy() const {
    OccupancyModel m;
    m.hit = log_odds(hit), m.miss = log_odds(miss), m.clamp_min = log_odds(min), m.clamp_max = log_odds(max);
    return m;
  }
};

struct Scene {
  Camera camera;
  Vec3 origin{0.0, 0.0, 1.0};
  Slab box{{1.4, -0.2, 0.8}, {1.6, 0.2, 1.2}};
  double wall = 3.0, resolution = 0.05;
  int most = 200;  // scans to wait for the box to clear; more: "never"
};

// Inserts one image: the points that returned, and (no_return) the NaN pixels' rays to max_range.
void insert(Octree& tree, const Scene& s, const Vec3& origin, const std::vector<Slab>& boxes, double wall, bool no_return,
            std::mt19937_64& rng) {
  std::vector<ScanPoint> world, optical, clear;
  image(s.camera, origin, boxes, wall, rng, world, optical);
  ScanOptions options;
  options.max_range = 4.0;
  options.threads = 1;
  if (no_return) {
    clear = no_return_ends(optical, s.camera.width, s.camera.height, s.camera.model, options.max_range);
    for (ScanPoint& p : clear) p = (s.camera.R * p.cast<double>() + origin).cast<float>();
  }
  insert_scan(tree, world, clear, origin.cast<float>(), options);
}

// Scans after the box is taken away until none of its voxels is occupied (most + 1: never).
int scans_to_clear(const Model& m, const Scene& s, int seen, double wall_after, bool no_return) {
  Octree tree(s.resolution, m.occupancy());
  std::mt19937_64 rng(1);
  for (int k = 0; k < seen; ++k) insert(tree, s, s.origin, {s.box}, s.wall, no_return, rng);
  const Vec3 lo = s.box.lo - Vec3::Constant(s.resolution), hi = s.box.hi + Vec3::Constant(s.resolution);
  for (int k = 1; k <= s.most; ++k) {
    insert(tree, s, s.origin, {}, wall_after, no_return, rng);
    if (occupied_in(tree, lo, hi) == 0) return k;
  }
  return s.most + 1;
}

// The share of (voxel, scan) readings that say free for an obstacle that is there all along, over
// `scans` scans after 10 of warming up. Its voxels are those any of its points fall in over the
// whole run (a first run, the same images, collects them).
double false_free(const Model& m, const Scene& s, const Slab& thing, bool moving, bool no_return, int scans) {
  // A camera on a moving base: sideways, a slow sway with a period of 3.7 s.
  auto camera_at = [&](int k) -> Vec3 { return s.origin + (moving ? Vec3(0.0, 0.3 * std::sin(2 * M_PI * k / 37.0), 0.0) : Vec3::Zero()); };
  const OctreeGrid grid(s.resolution);
  std::vector<OctreeKey> keys;
  {
    std::mt19937_64 rng(2);
    std::vector<ScanPoint> world, optical;
    for (int k = 0; k < 10 + scans; ++k) {
      image(s.camera, camera_at(k), {thing}, s.wall, rng, world, optical);
      for (const ScanPoint& p : world) {
        const Vec3 q = p.cast<double>();
        if ((q.array() < thing.lo.array() - 1e-3).any() || (q.array() > thing.hi.array() + 1e-3).any()) continue;
        const OctreeKey key = *grid.key(q);
        if (std::find(keys.begin(), keys.end(), key) == keys.end()) keys.push_back(key);
      }
    }
  }
  Octree tree(s.resolution, m.occupancy());
  std::mt19937_64 rng(2);
  double readings = 0, free = 0;
  for (int k = 0; k < 10 + scans; ++k) {
    insert(tree, s, camera_at(k), {thing}, s.wall, no_return, rng);
    if (k < 10) continue;
    for (const OctreeKey& key : keys) {
      const auto found = tree.find(key);
      readings += 1;
      free += !(found && tree.occupied(found->log_odds));
    }
  }
  return readings > 0 ? free / readings : 0.0;
}

std::string scans_cell(int scans, int most) { return scans > most ? "never" : std::to_string(scans); }

}  // namespace

void clearing_table(bool quick, const std::string& dir) {
  Scene s;
  const int w = quick ? 40 : 160, h = quick ? 30 : 120;
  Mat3 R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  s.camera = Camera{w, h, PinholeCamera{w * 0.75, w * 0.75, (w - 1) / 2.0, (h - 1) / 2.0}, R};
  s.most = quick ? 20 : 200;
  const int scans = quick ? 10 : 200;
  const std::vector<Model> models = {{"OctoMap's default", 0.7, 0.4, 0.1192, 0.971},
                                     {"lower upper clamp", 0.7, 0.4, 0.1192, 0.8},
                                     {"stronger miss", 0.7, 0.25, 0.1192, 0.971}};
  Table table("clearing", "Clearing: scans until a box that left is gone from the map, and what faster clearing costs",
              {"sensor model", "hit / miss / min / max", "scans to clear, seen 1 scan", "seen 10 scans",
               "seen 100 scans", "ms at 10 Hz, seen 100", "nothing behind it, OctoMap's rule (seen 10)",
               "nothing behind it, ~clear_no_return (seen 10)", "thin pole (8 mm), moving camera: voxel readings free %",
               "dark box (5 % returns), ~clear_no_return: voxel readings free %"});
  // The pole in the middle of its voxels' column (x 1.50-1.55, y 0-0.05), so that its points fall in one column.
  const Slab pole{{1.521, 0.021, 0.7}, {1.529, 0.029, 1.3}}, dark{{1.4, -0.2, 0.8}, {1.6, 0.2, 1.2}, 0.05};
  for (const Model& m : models) {
    const int after100 = scans_to_clear(m, s, 100, s.wall, false);
    const double inf = std::numeric_limits<double>::infinity();
    table.row({m.name, bench::format(m.hit) + " / " + bench::format(m.miss) + " / " + bench::format(m.min) + " / " +
                           bench::format(m.max),
               scans_cell(scans_to_clear(m, s, 1, s.wall, false), s.most), scans_cell(scans_to_clear(m, s, 10, s.wall, false), s.most),
               scans_cell(after100, s.most), after100 > s.most ? "never" : std::to_string(100 * after100),
               scans_cell(scans_to_clear(m, s, 10, inf, false), s.most), scans_cell(scans_to_clear(m, s, 10, inf, true), s.most),
               100.0 * false_free(m, s, pole, true, false, scans), 100.0 * false_free(m, s, dark, false, true, scans)});
  }
  table.note("A depth camera (" + std::to_string(w) + " x " + std::to_string(h) + " pixels, 75 degrees wide) 1.5 m from a "
             "40 x 40 x 40 cm box, a wall 3 m away, " + bench::format(s.resolution) + " m voxels, max_range 4 m; one scan "
             "is 100 ms at 10 Hz. 'Scans to clear': after the box is taken away, the scans until none of its voxels "
             "(centre within a voxel of the box) reads occupied; 'nothing behind it': the box is taken away and the "
             "pixels it covered return nothing (NaN): by OctoMap's rule they clear nothing. The last two columns are "
             "the cost: of the obstacle's voxel readings over " + std::to_string(scans) + " scans (after 10), the share "
             "that reads free although the obstacle is there. OctoMap's default needs 9 misses from its upper clamp "
             "(log-odds 3.48 / 0.41); a lower clamp or a stronger miss clears in 3-4.");
  table.write(dir);
}

}  // namespace bvh_collision::environment_bench
