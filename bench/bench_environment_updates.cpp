// Environment benchmark, its third unit: a map that changes. How long an obstacle that left stays
// in the map, and what faster clearing costs (table `clearing`); insertion against OctoMap per
// core, in CPU time, on a room's depth images and a LiDAR scan (table `insertion`).
// (environment_bench.h; main is in bench_environment.cpp.)
//
// A depth camera (pinhole, 10 Hz) looks along +x at a box in front of a wall. The box is seen for
// N scans and taken away; the table counts the scans until none of its voxels reads occupied,
// for OctoMap's default sensor model and two faster ones. The price of clearing faster is paid
// by obstacles the sensor sees badly: a pole thinner than a voxel seen by a moving camera (most
// rays through its voxel pass beside it), and a dark box that returns 5 % of its pixels (the rest
// are NaN, which clear along their ray under ~clear_no_return). Their columns count how often
// one of their voxels reads free.
#include <time.h>

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

namespace {

// CPU seconds of the whole process (every thread) spent in f.
template <class F>
double cpu_seconds(F&& f) {
  timespec a{}, b{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &a);
  f();
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &b);
  return double(b.tv_sec - a.tv_sec) + 1e-9 * double(b.tv_nsec - a.tv_nsec);
}

// The first hit of a ray among boxes (slabs), or infinity.
double first_hit(const Vec3& o, const Vec3& d, const std::vector<Slab>& boxes) {
  double best = std::numeric_limits<double>::infinity();
  for (const Slab& b : boxes) best = std::min(best, entry(o, d, b));
  return best;
}

// A room 6 x 5 x 3 m (walls, floor and ceiling as slabs) with a table, a shelf and boxes.
std::vector<Slab> room() {
  return {{{-0.1, 0, 0}, {0, 5, 3}},     {{6, 0, 0}, {6.1, 5, 3}},        {{0, -0.1, 0}, {6, 0, 3}},
          {{0, 5, 0}, {6, 5.1, 3}},      {{0, 0, -0.1}, {6, 5, 0}},       {{0, 0, 3}, {6, 5, 3.1}},
          {{2, 1.5, 0.7}, {3.2, 2.3, 0.75}}, {{4.5, 3.8, 0}, {5.8, 4.2, 2.0}}, {{2.3, 1.7, 0.75}, {2.5, 1.9, 0.95}},
          {{1.0, 3.5, 0}, {1.6, 4.1, 0.5}}};
}

// A 640 x 480 depth image (70 x 55 degrees) of the room from `camera` looking at `target`.
std::vector<ScanPoint> depth_image(const Vec3& camera, const Vec3& target, int step) {
  const std::vector<Slab> boxes = room();
  const Vec3 forward = (target - camera).normalized(), right = forward.cross(Vec3::UnitZ()).normalized();
  const Vec3 up = right.cross(forward);
  std::vector<ScanPoint> points;
  for (int v = 0; v < 480; v += step) {
    for (int u = 0; u < 640; u += step) {
      const Vec3 d = (forward + std::tan(0.61) * ((u + 0.5) / 320.0 - 1.0) * right +
                      std::tan(0.48) * (1.0 - (v + 0.5) / 240.0) * up).normalized();
      const double t = first_hit(camera, d, boxes);
      if (std::isfinite(t)) points.push_back((camera + t * d).cast<float>());
    }
  }
  return points;
}

// A 64-beam LiDAR (elevations -25 to +15 degrees, 1024 azimuths) 1.8 m up in a street: the
// ground and buildings between 12 and 60 m; beams that meet nothing return nothing.
std::vector<ScanPoint> lidar_scan(int step) {
  std::vector<Slab> boxes = {{{-100, -100, -0.1}, {100, 100, 0}}};
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> size(4, 12), height(3, 20), angle(0, 2 * M_PI), distance(12, 60);  // none holds the sensor
  for (int i = 0; i < 40; ++i) {
    const double a = angle(rng), r = distance(rng), w = size(rng);
    const Vec3 c(r * std::cos(a), r * std::sin(a), 0);
    boxes.push_back({c - Vec3(w / 2, w / 2, 0), c + Vec3(w / 2, w / 2, height(rng))});
  }
  const Vec3 sensor(0, 0, 1.8);
  std::vector<ScanPoint> points;
  for (int beam = 0; beam < 64; beam += step) {
    const double elevation = (-25.0 + 40.0 * beam / 63.0) * M_PI / 180.0;
    for (int k = 0; k < 1024; k += step) {
      const double azimuth = 2 * M_PI * k / 1024.0;
      const Vec3 d(std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
      const double t = first_hit(sensor, d, boxes);
      if (std::isfinite(t) && t < 120.0) points.push_back((sensor + t * d).cast<float>());
    }
  }
  return points;
}

struct Cloud {
  std::string name;
  std::vector<std::vector<ScanPoint>> scans;  // inserted in turn into one tree
  std::vector<Vec3> origins;
  double max_range;
  std::vector<double> resolutions;
  int runs;  // medians of this many (fewer for the long ones)
};

struct Timing {
  double ours_one_core = 0, ours_default_walk = 0, ours_two_cores_wall = 0, ours_two_cores_cpu = 0, octomap = 0;
  bool identical = true;
};

Timing time_insertion(const Cloud& c, double resolution, int runs) {
  std::vector<double> one, generic, two_wall, two_cpu, theirs;
  bool identical = true;
  for (int r = 0; r < runs; ++r) {
    Octree a(resolution), b(resolution), g(resolution);
    octomap::OcTree reference(resolution);
    ScanOptions single, pair;
    single.max_range = pair.max_range = c.max_range;
    single.threads = 1;
    pair.threads = 2;
    one.push_back(cpu_seconds([&] {
      for (std::size_t i = 0; i < c.scans.size(); ++i) insert_scan(a, c.scans[i], c.origins[i].cast<float>(), single);
    }));
    ScanOptions plain = single;  // the default build's walk, as on a CPU without AVX2
    plain.simd = SimdPath::kGeneric;
    generic.push_back(cpu_seconds([&] {
      for (std::size_t i = 0; i < c.scans.size(); ++i) insert_scan(g, c.scans[i], c.origins[i].cast<float>(), plain);
    }));
    double wall = 0.0;
    two_cpu.push_back(cpu_seconds([&] {
      wall = 1e-6 * bench::time_us([&] {
        for (std::size_t i = 0; i < c.scans.size(); ++i) insert_scan(b, c.scans[i], c.origins[i].cast<float>(), pair);
      });
    }));
    two_wall.push_back(wall);
    theirs.push_back(cpu_seconds([&] {
      for (std::size_t i = 0; i < c.scans.size(); ++i) {
        octomap::Pointcloud cloud;
        for (const ScanPoint& p : c.scans[i]) cloud.push_back(p.x(), p.y(), p.z());
        reference.insertPointCloud(cloud, octomap::point3d(c.origins[i].x(), c.origins[i].y(), c.origins[i].z()), c.max_range);
      }
    }));
    if (r == 0) {
      const LeafMap theirs_leaves = leaves_of(reference);
      identical = leaves_of(a) == theirs_leaves && leaves_of(b) == theirs_leaves && leaves_of(g) == theirs_leaves;
    }
  }
  return {bench::median(one), bench::median(generic), bench::median(two_wall), bench::median(two_cpu), bench::median(theirs), identical};
}

}  // namespace

void insertion_cpu_table(bool quick, const std::string& dir) {
  const int step = quick ? 8 : 1;
  const Vec3 camera(0.4, 0.4, 1.6);
  const std::vector<double> both = quick ? std::vector<double>{0.05} : std::vector<double>{0.05, 0.02};
  const int runs = quick ? 1 : 3;
  const std::vector<ScanPoint> image = depth_image(camera, {3, 2.5, 0.8}, step), lidar = lidar_scan(step);
  // A LiDAR's free space at 2 cm out to 30 m is some hundred million voxels (OctoMap's tree took
  // 19 GB here): its 2 cm row is at 10 m.
  std::vector<Cloud> clouds = {{"room, depth image, unlimited range", {image}, {camera}, -1.0, both, runs},
                               {"room, depth image, 5 m range", {image}, {camera}, 5.0, both, runs},
                               {"street, 64-beam LiDAR, 30 m range", {lidar}, {Vec3(0, 0, 1.8)}, 30.0, {0.05}, runs},
                               {"street, 64-beam LiDAR, 10 m range", {lidar}, {Vec3(0, 0, 1.8)}, 10.0, both, runs}};
  Cloud ten{"room, ten depth images into one tree, 5 m range", {}, {}, 5.0, both, 1};
  for (int k = 0; k < (quick ? 2 : 10); ++k) {
    const double a = 2 * M_PI * k / 10.0;
    const Vec3 at(3 + 2.2 * std::cos(a), 2.5 + 1.8 * std::sin(a), 1.2 + 0.3 * std::sin(3 * a));
    ten.scans.push_back(depth_image(at, {3 - 0.5 * std::cos(a), 2.5, 0.6}, step));
    ten.origins.push_back(at);
  }
  clouds.push_back(ten);
  Table table("insertion", "Insertion per core against OctoMap (CPU time), depth images and LiDAR",
              {"cloud", "resolution m", "points", "OctoMap CPU s", "ours one core CPU s", "OctoMap / ours, per core",
               "OctoMap / ours, per core, default build's walk (SSE2)", "ours two cores wall s", "ours two cores CPU s",
               "identical trees"});
  for (const Cloud& c : clouds) {
    std::size_t points = 0;
    for (const auto& s : c.scans) points += s.size();
    for (const double res : c.resolutions) {
      const Timing t = time_insertion(c, res, c.runs);
      table.row({c.name, res, double(points), t.octomap, t.ours_one_core, t.octomap / t.ours_one_core,
                 t.octomap / t.ours_default_walk, t.ours_two_cores_wall, t.ours_two_cores_cpu, t.identical ? "yes" : "NO"});
    }
  }
  table.note("CPU time of the whole process (clock_gettime(CLOCK_PROCESS_CPUTIME_ID)), medians of " + std::to_string(runs) +
             " runs (one for the ten images): 'per core' compares OctoMap 1.9's insertPointCloud with ours on one thread (ScanOptions::threads = 1), "
             "so another load on the machine does not move the ratio much; the two-core columns are ours on two threads. "
             "Our rays' walk is built twice and the CPU's best taken at run time (ScanOptions::simd): 'per core' is "
             "that one (" + std::string(avx2_available() ? "AVX2" : "the default build: no AVX2") + " here); the "
             "default build's column is the same run with the walk plain x86-64 (SSE2) takes, as on a CPU without AVX2. "
             "No workspace box (OctoMap's insertPointCloud without a bounding box). 'identical trees': every leaf, depth "
             "and log-odds equal to OctoMap's, one core and two.");
  table.write(dir);
}

}  // namespace bvh_collision::environment_bench
