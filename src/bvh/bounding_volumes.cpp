#include "bvh_collision/bvh/bounding_volumes.h"

#include <Eigen/Eigenvalues>
#include <optional>
#include <vector>

namespace bvh_collision {
namespace {

// Grows a fitted interval by a few ulps of its magnitude: projections onto non-axis directions
// round, and a volume must contain its points.
void pad_interval(double& lo, double& hi) {
  const double m = 8 * std::numeric_limits<double>::epsilon() * (std::abs(lo) + std::abs(hi));
  lo -= m;
  hi += m;
}

// Extents of points along the columns of `axes`.
void project_extents(const Vec3* p, std::size_t n, const Mat3& axes, Vec3& lo, Vec3& hi) {
  lo = Vec3::Constant(std::numeric_limits<double>::infinity());
  hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 q = axes.transpose() * p[i];
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  for (int k = 0; k < 3; ++k) pad_interval(lo[k], hi[k]);
}

template <int K>
Kdop<K> fit_kdop(const Vec3* p, std::size_t n) {
  Kdop<K> k;
  for (std::size_t i = 0; i < n; ++i) k.extend(p[i]);
  for (int s = 3; s < Kdop<K>::kSlabs; ++s) pad_interval(k.lo[s], k.hi[s]);
  return k;
}

}  // namespace

namespace detail {

Mat3 principal_axes(const Vec3* points, std::size_t n) {
  if (n == 0) return Mat3::Identity();
  Vec3 mean = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) mean += points[i];
  mean /= static_cast<double>(n);
  Mat3 cov = Mat3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = points[i] - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(cov);
  const Mat3 v = solver.eigenvectors();  // ascending eigenvalues
  Mat3 axes;
  axes.col(0) = v.col(2).normalized();
  axes.col(1) = v.col(1).normalized();
  axes.col(2) = axes.col(0).cross(axes.col(1)).normalized();
  if (!axes.allFinite()) return Mat3::Identity();
  return axes;
}

}  // namespace detail

template <>
Aabb fit_volume<Aabb>(const Vec3* points, std::size_t n) {
  Aabb b;
  for (std::size_t i = 0; i < n; ++i) b.extend(points[i]);  // min/max are exact: no padding
  return b;
}

namespace {

// Volume of the box with these axes around the points (padded so flat boxes still compare).
double box_volume(const Vec3* points, std::size_t n, const Mat3& axes, double pad) {
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 q = axes.transpose() * points[i];
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const Vec3 e = hi - lo + Vec3::Constant(pad);
  return e.x() * e.y() * e.z();
}

Mat3 rotated_about(const Mat3& axes, int k, double angle) {
  const double c = std::cos(angle), s = std::sin(angle);
  const int i = (k + 1) % 3, j = (k + 2) % 3;
  Mat3 r = axes;
  r.col(i) = c * axes.col(i) + s * axes.col(j);
  r.col(j) = -s * axes.col(i) + c * axes.col(j);
  return r;
}

// The orientation of a tight box: the better of the principal axes and the mesh axes, refined
// by a coarse-to-fine search over rotations about each axis. Tighter boxes mean fewer overlap
// tests in every query, which repays the build-time search. Over kSearchPoints points the
// search looks at an evenly strided subset (the box itself still takes in every point): the
// nodes that large are few, and searching all their points made a 200k-vertex mesh's build
// O(n log n) times a hundred volume evaluations.
Mat3 tight_box_axes(const Vec3* points, std::size_t n, bool search) {
  constexpr std::size_t kSearchPoints = 2048;
  std::vector<Vec3> subset;
  if (n > kSearchPoints) {
    subset.reserve(kSearchPoints);
    for (std::size_t i = 0; i < kSearchPoints; ++i) subset.push_back(points[i * n / kSearchPoints]);
    points = subset.data();
    n = subset.size();
  }
  Vec3 lo = points[0], hi = points[0];
  for (std::size_t i = 1; i < n; ++i) {
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  const double pad = 1e-3 * (hi - lo).norm() + 1e-300;
  Mat3 best = detail::principal_axes(points, n);
  double best_volume = box_volume(points, n, best, pad);
  if (const double v = box_volume(points, n, Mat3::Identity(), pad); v < best_volume) {
    best = Mat3::Identity();
    best_volume = v;
  }
  for (double step = 0.2; search && step > 0.005; step *= 0.5) {
    bool improved = true;
    while (improved) {
      improved = false;
      for (int k = 0; k < 3; ++k) {
        for (double angle : {step, -step}) {
          const Mat3 candidate = rotated_about(best, k, angle);
          const double v = box_volume(points, n, candidate, pad);
          if (v < best_volume * (1 - 1e-9)) {
            best = candidate;
            best_volume = v;
            improved = true;
          }
        }
      }
    }
  }
  return best;
}

// Without the search: the principal axes (from sums shifted to the first point, in the same pass
// that finds the axis-aligned box) or the mesh axes, whichever box is smaller. Two passes over
// the points instead of six.
Mat3 quick_box_axes(const Vec3* points, std::size_t n) {
  const Vec3 origin = points[0];
  Vec3 sum = Vec3::Zero(), lo = origin, hi = origin;
  Mat3 products = Mat3::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = points[i] - origin;
    sum += d;
    products += d * d.transpose();
    lo = lo.cwiseMin(points[i]);
    hi = hi.cwiseMax(points[i]);
  }
  const Vec3 mean = sum / static_cast<double>(n);
  const Eigen::SelfAdjointEigenSolver<Mat3> solver(products / static_cast<double>(n) - mean * mean.transpose());
  Mat3 axes;
  axes.col(0) = solver.eigenvectors().col(2).normalized();
  axes.col(1) = solver.eigenvectors().col(1).normalized();
  axes.col(2) = axes.col(0).cross(axes.col(1)).normalized();
  if (!axes.allFinite()) return Mat3::Identity();
  const double pad = 1e-3 * (hi - lo).norm() + 1e-300;
  const Vec3 e = hi - lo + Vec3::Constant(pad);
  return box_volume(points, n, axes, pad) < e.x() * e.y() * e.z() ? axes : Mat3::Identity();
}

// A single triangle's tightest box lies in its plane with one side along an edge (the smallest
// rectangle around a convex polygon is flush with one of its edges): three candidates instead of
// the search, for the leaves, which are half of every tree's nodes. None for a degenerate one.
std::optional<Mat3> triangle_box_axes(const Vec3* p) {
  const Vec3 normal = (p[1] - p[0]).cross(p[2] - p[0]);
  if (!(normal.norm() > 0.0) || !normal.allFinite()) return std::nullopt;
  std::optional<Mat3> best;
  double best_area = std::numeric_limits<double>::infinity();
  for (int e = 0; e < 3; ++e) {
    Mat3 axes;
    axes.col(0) = (p[(e + 1) % 3] - p[e]).normalized();
    axes.col(2) = normal.normalized();
    axes.col(1) = axes.col(2).cross(axes.col(0)).normalized();
    if (!axes.allFinite()) continue;
    Vec3 lo, hi;
    project_extents(p, 3, axes, lo, hi);
    if (const double area = (hi.x() - lo.x()) * (hi.y() - lo.y()); area < best_area) {
      best_area = area;
      best = axes;
    }
  }
  return best;
}

}  // namespace

Obb fit_obb(const Vec3* points, std::size_t n, bool search_rotations) {
  Obb b;
  if (n == 0) return b;
  const std::optional<Mat3> flat = n == 3 ? triangle_box_axes(points) : std::nullopt;
  b.axes = flat ? *flat : search_rotations ? tight_box_axes(points, n, true) : quick_box_axes(points, n);
  Vec3 lo, hi;
  project_extents(points, n, b.axes, lo, hi);
  b.center = b.axes * (0.5 * (lo + hi));
  b.half = 0.5 * (hi - lo);
  b.radius = b.half.norm() * (1 + 4 * std::numeric_limits<double>::epsilon());
  return b;
}

template <>
Obb fit_volume<Obb>(const Vec3* points, std::size_t n) {
  return fit_obb(points, n, true);
}

template <>
Sphere fit_volume<Sphere>(const Vec3* p, std::size_t n) {
  Sphere s;
  if (n == 0) return s;
  // Ritter: a diameter from two far-apart points, then grow to take in the rest.
  auto farthest = [&](const Vec3& from) {
    std::size_t best = 0;
    for (std::size_t i = 1; i < n; ++i) {
      if ((p[i] - from).squaredNorm() > (p[best] - from).squaredNorm()) best = i;
    }
    return best;
  };
  const std::size_t y = farthest(p[0]);
  const std::size_t z = farthest(p[y]);
  s.center = 0.5 * (p[y] + p[z]);
  s.radius = 0.5 * (p[y] - p[z]).norm();
  for (std::size_t i = 0; i < n; ++i) {
    const double d = (p[i] - s.center).norm();
    if (d > s.radius) {
      const double r = 0.5 * (s.radius + d);
      s.center += ((r - s.radius) / d) * (p[i] - s.center);
      s.radius = r;
    }
  }
  // The box centre sometimes does better; keep the smaller, with its radius measured exactly.
  const Aabb box = fit_volume<Aabb>(p, n);
  double r_ritter = 0.0, r_box = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    r_ritter = std::max(r_ritter, (p[i] - s.center).norm());
    r_box = std::max(r_box, (p[i] - center(box)).norm());
  }
  if (r_box < r_ritter) {
    s.center = center(box);
    r_ritter = r_box;
  }
  s.radius = r_ritter * (1 + 4 * std::numeric_limits<double>::epsilon()) +
             4 * std::numeric_limits<double>::epsilon() * s.center.cwiseAbs().sum();
  return s;
}

template <>
Rss fit_volume<Rss>(const Vec3* points, std::size_t n) {
  Rss r;
  r.axes = detail::principal_axes(points, n);  // the rectangle spans the two widest directions
  Vec3 lo, hi;
  project_extents(points, n, r.axes, lo, hi);
  r.center = r.axes * (0.5 * (lo + hi));
  r.half[0] = 0.5 * (hi[0] - lo[0]);
  r.half[1] = 0.5 * (hi[1] - lo[1]);
  r.radius = 0.5 * (hi[2] - lo[2]);
  return r;
}

template <>
Kdop14 fit_volume<Kdop14>(const Vec3* p, std::size_t n) { return fit_kdop<14>(p, n); }
template <>
Kdop18 fit_volume<Kdop18>(const Vec3* p, std::size_t n) { return fit_kdop<18>(p, n); }
template <>
Kdop26 fit_volume<Kdop26>(const Vec3* p, std::size_t n) { return fit_kdop<26>(p, n); }

Obb merge(const Obb& a, const Obb& b) {
  // The textbook's method: refit to the 16 corners.
  Vec3 corners[16];
  for (int i = 0; i < 8; ++i) {
    const Vec3 s((i & 4) ? 1 : -1, (i & 2) ? 1 : -1, (i & 1) ? 1 : -1);
    corners[i] = a.center + a.axes * s.cwiseProduct(a.half);
    corners[8 + i] = b.center + b.axes * s.cwiseProduct(b.half);
  }
  return fit_volume<Obb>(corners, 16);
}

Rss merge(const Rss& a, const Rss& b) {
  // Fit a rectangle swept sphere to the 8 rectangle corners; it holds both rectangles, so
  // adding the larger radius holds both volumes.
  Vec3 corners[8];
  for (int i = 0; i < 4; ++i) {
    const double sx = (i & 2) ? 1 : -1, sy = (i & 1) ? 1 : -1;
    corners[i] = a.center + a.axes.col(0) * (sx * a.half[0]) + a.axes.col(1) * (sy * a.half[1]);
    corners[4 + i] = b.center + b.axes.col(0) * (sx * b.half[0]) + b.axes.col(1) * (sy * b.half[1]);
  }
  Rss m = fit_volume<Rss>(corners, 8);
  m.radius += std::max(a.radius, b.radius);
  return m;
}

bool contains(const Aabb& v, const Vec3& p) {
  return (p.array() >= v.min.array()).all() && (p.array() <= v.max.array()).all();
}

bool contains(const Obb& v, const Vec3& p) {
  const Vec3 q = v.axes.transpose() * (p - v.center);
  const double pad = kVolumeMargin * (v.half.sum() + v.center.cwiseAbs().sum() + 1e-300);
  return (q.cwiseAbs().array() <= v.half.array() + pad).all();
}

bool contains(const Sphere& v, const Vec3& p) {
  return (p - v.center).norm() <= v.radius * (1 + kVolumeMargin) + kVolumeMargin * v.center.cwiseAbs().sum();
}

bool contains(const Rss& v, const Vec3& p) {
  const Vec3 q = v.axes.transpose() * (p - v.center);
  const Vec3 on_rect(std::clamp(q.x(), -v.half[0], v.half[0]), std::clamp(q.y(), -v.half[1], v.half[1]), 0.0);
  const double pad = kVolumeMargin * (v.half[0] + v.half[1] + v.radius + v.center.cwiseAbs().sum());
  return (q - on_rect).norm() <= v.radius + pad;
}

template <>
const char* volume_name<Aabb>() { return "AABB"; }
template <>
const char* volume_name<Obb>() { return "OBB"; }
template <>
const char* volume_name<Sphere>() { return "sphere"; }
template <>
const char* volume_name<Kdop14>() { return "14-DOP"; }
template <>
const char* volume_name<Kdop18>() { return "18-DOP"; }
template <>
const char* volume_name<Kdop26>() { return "26-DOP"; }
template <>
const char* volume_name<Rss>() { return "RSS"; }

}  // namespace bvh_collision
