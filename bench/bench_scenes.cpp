// The benchmarks' scenes (bench_scenes.h).
#include "bench_scenes.h"

#include <cmath>
#include <limits>
#include <random>

namespace bvh_collision::environment_bench {
namespace {

struct SceneBox {
  Vec3 lo, hi;
};

}  // namespace

std::vector<ScanPoint> table_scene(const Vec3& camera, const ExtraHit& extra, int width, int height, unsigned seed) {
  const std::vector<SceneBox> boxes = {
      {{0.3, -0.6, 0.30}, {1.0, 0.6, 0.35}},   // table top
      {{0.5, -0.2, 0.35}, {0.6, -0.1, 0.50}},  // a box
      {{0.7, 0.1, 0.35}, {0.8, 0.3, 0.45}},    // another
      {{-5, -5, -0.1}, {5, 5, 0.0}},           // floor
      {{2.5, -5, 0.0}, {2.6, 5, 3.0}},         // wall
  };
  const Vec3 forward = Vec3(1.0, 0.0, -0.8).normalized(), right = Vec3(0, -1, 0), up = right.cross(forward) * -1.0;
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.002);
  std::vector<ScanPoint> points;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const double x = std::tan(0.61) * (2.0 * (u + 0.5) / width - 1.0), y = std::tan(0.51) * (2.0 * (v + 0.5) / height - 1.0);
      const Vec3 d = (forward + x * right + y * up).normalized();
      double best = std::numeric_limits<double>::infinity();
      for (const SceneBox& b : boxes) {
        double t0 = 0.0, t1 = best;
        for (int a = 0; a < 3 && t0 <= t1; ++a) {
          const double s1 = (b.lo[a] - camera[a]) / d[a], s2 = (b.hi[a] - camera[a]) / d[a];
          t0 = std::max(t0, std::min(s1, s2));
          t1 = std::min(t1, std::max(s1, s2));
        }
        if (t0 <= t1) best = t0;
      }
      if (extra) best = extra(camera, d, best);
      const float nan = std::numeric_limits<float>::quiet_NaN();
      points.push_back(std::isfinite(best) && best < 6.0 ? ScanPoint((camera + (best + noise(rng)) * d).cast<float>())
                                                         : ScanPoint(nan, nan, nan));
    }
  }
  return points;
}

std::vector<ScanPoint> demo_pillar() {
  std::vector<ScanPoint> pillar;
  const Vec3 lo(0.39, 0.29, 0.0), hi(0.51, 0.41, 0.8);
  for (double x = lo.x(); x <= hi.x() + 1e-9; x += 0.01) {
    for (double y = lo.y(); y <= hi.y() + 1e-9; y += 0.01) {
      for (double z = lo.z(); z <= hi.z() + 1e-9; z += 0.01) {
        const bool surface = x < lo.x() + 0.005 || x > hi.x() - 0.005 || y < lo.y() + 0.005 || y > hi.y() - 0.005 ||
                             z < lo.z() + 0.005 || z > hi.z() - 0.005;
        if (surface) pillar.emplace_back(float(x), float(y), float(z));
      }
    }
  }
  return pillar;
}

std::vector<ScanPoint> noisy_copy(const std::vector<ScanPoint>& points, float sigma, std::mt19937_64& rng) {
  std::normal_distribution<float> noise(0.0f, sigma);
  std::vector<ScanPoint> out;
  out.reserve(points.size());
  for (const ScanPoint& p : points) out.emplace_back(p.x() + noise(rng), p.y() + noise(rng), p.z() + noise(rng));
  return out;
}

}  // namespace bvh_collision::environment_bench
