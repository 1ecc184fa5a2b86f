// The greedy start of a link proxy's cover (proxy_build.h): candidate spheres through sampled
// surface points and on an interior grid, chosen by a greedy set cover of the samples.
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>

#include "proxy_build.h"
#include "proxy_build_index.h"

namespace bvh_collision {
namespace proxy_build {
namespace {
// Points of the shape's surface about `spacing` apart, each with its inward direction (zero when
// unknown): a barycentric grid on every triangle, or the box's surface grid carried to a
// primitive's surface.
std::vector<std::pair<Vec3, Vec3>> surface_samples(const ShapeField& field, double spacing) {
  std::vector<std::pair<Vec3, Vec3>> out;
  if (!field.faces.empty() || field.mesh) {
    for (const Triangle& t : field.faces.empty() ? field.mesh->triangles() : field.faces) {
      const Vec3 normal = (t[1] - t[0]).cross(t[2] - t[0]);
      const Vec3 inward = normal.norm() > 0.0 ? Vec3(-normal.normalized()) : Vec3::Zero();
      // Along the edges every `spacing`, inside one point per spacing^2 of area (a long sliver
      // gets a line of points, not a grid).
      for (int e = 0; e < 3; ++e) {
        const Vec3 a = t[e], b = t[(e + 1) % 3];
        const int k = std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing)));
        for (int i = 0; i < k; ++i) out.emplace_back(a + (b - a) * (double(i) / k), inward);
      }
      const int inner = static_cast<int>(0.5 * normal.norm() / (spacing * spacing));
      for (int i = 0; i < inner; ++i) {  // a low-discrepancy fold of the unit square onto the triangle
        double u = std::fmod(0.5 + i * 0.7548776662466927, 1.0), v = std::fmod(0.5 + i * 0.5698402909980532, 1.0);
        if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
        out.emplace_back(t[0] + u * (t[1] - t[0]) + v * (t[2] - t[0]), inward);
      }
    }
    return out;
  }
  const Vec3 half = half_extents(field.primitive) * (1.0 + 1e-6);
  const Eigen::Vector3i n = (2.0 * half / spacing).array().ceil().cast<int>().max(1);
  for (int x = 0; x <= n.x(); ++x) {
    for (int y = 0; y <= n.y(); ++y) {
      for (int z = 0; z <= n.z(); ++z) {
        if (x != 0 && x != n.x() && y != 0 && y != n.y() && z != 0 && z != n.z()) continue;
        const Vec3 p = -half + Vec3(2.0 * half.x() * x / n.x(), 2.0 * half.y() * y / n.y(), 2.0 * half.z() * z / n.z());
        out.emplace_back(closest_point(field.primitive, p), Vec3::Zero());
      }
    }
  }
  return out;
}

// Grid points inside the solid, about `spacing` apart, each with its depth (into `depths`). A
// point's depth is at most the last point's plus the step between them (depth is 1-Lipschitz),
// which bounds its nearest search (the same depth, with room above it for rounding, found
// sooner); a point within the last one's free ball (the step below its depth, by more than
// rounding) is in the solid too, as its ray would say (no surface between them).
std::vector<Vec3> interior_points(const ShapeField& field, double spacing, std::vector<double>& depths) {
  std::vector<Vec3> out;
  depths.clear();
  if (!field.solid()) return out;
  const auto [center, half] = field.box();
  const Eigen::Vector3i n = (2.0 * half / spacing).array().ceil().cast<int>().max(1);
  Vec3 before = Vec3::Zero();
  double depth_before = std::numeric_limits<double>::infinity(), step = 0.0;
  const auto within_ball = [&](const Vec3& p) {
    step = (p - before).norm();
    return !out.empty() && step < depth_before * (1.0 - 1e-9) - 1e-12;
  };
  for (int x = 0; x < n.x(); ++x) {
    for (int y = 0; y < n.y(); ++y) {
      for (int z = 0; z < n.z(); ++z) {
        const Vec3 p = center - half + Vec3((x + 0.5) * 2.0 * half.x() / n.x(), (y + 0.5) * 2.0 * half.y() / n.y(),
                                            (z + 0.5) * 2.0 * half.z() / n.z());
        if (!within_ball(p) && !field.inside(p)) continue;
        const double limit = (depth_before + step) * (1.0 + 1e-9) + 1e-12;
        depth_before = field.surface_distance(p, true, limit, nullptr);
        before = p;
        out.push_back(p);
        depths.push_back(depth_before);
      }
    }
  }
  return out;
}


// The greedy set cover: the candidate covering the most targets not yet covered, until none
// covers one more; of equal gains, the later candidate. Lazily: a candidate's gain only falls as
// targets are covered, so a gain counted earlier bounds the true one, and the candidate on top of
// the queue whose recount equals its entry has the largest true gain of all. The targets each
// candidate covers are kept flat (first[c] .. first[c + 1] in covers), and a recount reads those
// it left uncovered (first[c] .. end[c]).
std::vector<Chosen> choose_cover(const std::vector<Vec3>& targets, const std::vector<Chosen>& candidates, double margin) {
  const PointTree tree(targets);
  std::vector<std::uint32_t> covers, first(candidates.size() + 1, 0);
  for (std::size_t c = 0; c < candidates.size(); ++c) {
    tree.in_ball(candidates[c].center, std::max(0.0, candidates[c].radius - margin), [&](std::uint32_t t) { covers.push_back(t); });
    first[c + 1] = static_cast<std::uint32_t>(covers.size());
  }
  std::priority_queue<std::pair<std::size_t, std::size_t>> queue;  // (gain when counted, candidate)
  for (std::size_t c = 0; c < candidates.size(); ++c) queue.emplace(first[c + 1] - first[c], c);
  std::vector<char> covered(targets.size(), 0);
  std::vector<std::uint32_t> end(first.begin() + 1, first.end());  // a recount keeps the uncovered before it
  std::vector<Chosen> chosen;
  while (!queue.empty()) {
    const auto [gain, c] = queue.top();
    queue.pop();
    std::uint32_t now = first[c];
    for (std::uint32_t k = first[c]; k < end[c]; ++k) {
      covers[now] = covers[k];
      now += covered[covers[k]] == 0;
    }
    end[c] = now;  // (a target once covered stays covered: the next recount reads only the rest)
    if (now == first[c]) continue;
    if (now - first[c] < gain) {
      queue.emplace(now - first[c], c);
      continue;
    }
    for (std::uint32_t k = first[c]; k < end[c]; ++k) covered[covers[k]] = 1;
    chosen.push_back(candidates[c]);
  }
  return chosen;
}

}  // namespace

// Greedy set cover of sample points by candidate spheres. Only an efficiency step: the covers
// prove what they keep and fill whatever the samples missed.
std::vector<Chosen> greedy_seed(const ShapeField& field, double half_level, double margin) {
  const double size = field.box().second.maxCoeff();
  const double spacing = std::max(half_level, size / 24.0);
  const SeedBuilder builder(field, half_level);
  std::vector<Vec3> targets;
  std::vector<Chosen> candidates;
  std::size_t sample = 0;
  for (const auto& [q, inward] : surface_samples(field, spacing)) {
    targets.push_back(q);
    // Candidates from every third sample: as good a cover (docs/performance.md), a third of the build.
    if (!field.solid()) {  // a surface only: balls of radius e/2 centred on it
      candidates.push_back({q, half_level * (1.0 - kVolumeMargin) - kVolumeMargin});
      continue;
    }
    if (sample++ % 3 == 0 && inward.squaredNorm() > 0.0) {
      if (auto s = builder.medial_sphere(q, inward, 2.0 * size)) candidates.push_back(*s);
    }
  }
  std::vector<double> depths;
  const std::vector<Vec3> inner = interior_points(field, std::max(spacing, size / 12.0), depths);
  for (std::size_t i = 0; i < inner.size(); ++i) {
    targets.push_back(inner[i]);
    candidates.push_back(builder.interior_sphere(inner[i], depths[i]));
  }
  field.stats->candidates += candidates.size();
  return choose_cover(targets, candidates, margin);
}

}  // namespace proxy_build
}  // namespace bvh_collision
