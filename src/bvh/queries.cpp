#include "bvh_collision/bvh/queries.h"
#include "bvh_collision/geometry/detail/filtered_predicates.h"
#include "bvh_collision/bvh/traversal.h"
#include "bvh_collision/geometry/safety_margin.h"

#include <algorithm>
#include <array>

#include "bvh_collision/geometry/distance.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision {
namespace {

Triangle carried(const Triangle& t, const RelativeFrame& f) {
  if (f.pure_translation) return Triangle{{t[0] + f.t, t[1] + f.t, t[2] + f.t}};
  return Triangle{{f.apply(t[0]), f.apply(t[1]), f.apply(t[2])}};
}

Vec3 unit_normal(const Triangle& t) {
  const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
  const double len = n.norm();
  return len > 0.0 ? Vec3(n / len) : Vec3(Vec3::UnitZ());
}

// How far the vertices of `s` reach behind the plane of `t` (0 when none do).
double penetration_behind(const Triangle& s, const Triangle& t) {
  const Vec3 n = unit_normal(t);
  double depth = 0.0;
  for (int i = 0; i < 3; ++i) depth = std::max(depth, -(s[i] - t[0]).dot(n));
  return depth;
}

// ------------------------------------------------------------------------------------ collide

template <class BV>
class CollisionTraversal {
 public:
  CollisionTraversal(const Bvh<BV>& a, const Bvh<BV>& b, const Transform& pose_a, const Transform& pose_b,
                     const CollisionRequest& request, CollisionResult& result)
      : a_(a), b_(b), pose_a_(pose_a), frame_(RelativeFrame::from(relative_transform(pose_a, pose_b))),
        request_(request), result_(result) {}

  void run() {
    if constexpr (CarriesVolumes<BV>::value) {
      // Looked up once per query: thread_local access costs a call in a shared library.
      thread_local CarryCache cache;
      cache_ = &cache;
      ++cache.query;  // a new stamp: volumes carried by earlier queries are stale
      if (cache.carried.size() < b_.nodes().size()) {
        cache.carried.resize(b_.nodes().size());
        cache.stamp.resize(b_.nodes().size(), 0);
      }
    }
    auto visit = [this](std::int32_t a, std::int32_t b) {
      const BvhNode<BV>& na = a_.nodes()[a];
      const BvhNode<BV>& nb = b_.nodes()[b];
      ++result_.stats.volume_tests;
      if (!overlaps(na.volume, b)) return Visit::kSkip;
      if (request_.max_contacts == 0 && request_.tolerance > 0.0 && na.slack + nb.slack <= request_.tolerance) {
        result_.collision = result_.within_tolerance = true;  // d <= padding + tolerance
        return Visit::kStop;
      }
      return Visit::kEnter;
    };
    auto leaf = [this](const BvhNode<BV>& na, const BvhNode<BV>& nb) {
      leaf_pair(na, nb);
      return done();
    };
    depth_first_pair(a_, b_, visit, leaf, [this](const BvhNode<BV>& na, const BvhNode<BV>& nb, bool split_a) {
      return left_nearer(na, nb, split_a);
    });
  }

 private:
  // b's volumes carried into a's frame, once per node and query, for types where that pays.
  bool overlaps(const BV& va, std::int32_t b) {
    if constexpr (CarriesVolumes<BV>::value) {
      CarryCache& cache = *cache_;
      if (cache.stamp[b] != cache.query) {
        cache.carried[b] = carry(b_.nodes()[b].volume, frame_);
        cache.stamp[b] = cache.query;
        ++result_.stats.volume_updates;
      }
      return overlap_carried(va, cache.carried[b], request_.padding);
    } else {
      return overlap(va, b_.nodes()[b].volume, frame_, request_.padding);
    }
  }

  // The child pair whose centres are closer is entered first: a penetration is reached in
  // fewer steps, which is what a boolean query (stopping at the first contact) pays for.
  bool left_nearer(const BvhNode<BV>& na, const BvhNode<BV>& nb, bool split_a) const {
    if (split_a) {
      const Vec3 cb = frame_.apply(center(nb.volume));
      return (center(a_.nodes()[na.left].volume) - cb).squaredNorm() <=
             (center(a_.nodes()[na.right].volume) - cb).squaredNorm();
    }
    const Vec3 ca = center(na.volume);
    return (frame_.apply(center(b_.nodes()[nb.left].volume)) - ca).squaredNorm() <=
           (frame_.apply(center(b_.nodes()[nb.right].volume)) - ca).squaredNorm();
  }

  bool done() const {
    return result_.collision && (request_.max_contacts == 0 || result_.contacts.size() >= request_.max_contacts);
  }

  void leaf_pair(const BvhNode<BV>& na, const BvhNode<BV>& nb) {
    for (std::int32_t j = nb.first; j < nb.first + nb.count; ++j) {
      const Triangle tb = carried(b_.triangles()[j], frame_);
      const TrianglePlane pb = detail::plane_of(tb[0], tb[1], tb[2]);
      const Vec3 cb = frame_.apply(b_.spheres()[j].center);
      for (std::int32_t i = na.first; i < na.first + na.count; ++i) {
        ++result_.stats.primitive_tests;
        const Triangle& ta = a_.triangles()[i];
        if (request_.padding == 0.0) {
          // Certified float plane tests first; the exact test only when they cannot tell.
          if (detail::plane_separates(pb, ta[0], ta[1], ta[2]) ||
              detail::plane_separates(a_.planes()[i], tb[0], tb[1], tb[2])) {
            continue;
          }
          if (!triangles_intersect(ta, tb)) continue;
          record(ta, tb, i, j, nullptr);
        } else {
          const double reach = request_.padding + a_.spheres()[i].radius + b_.spheres()[j].radius;
          const double grown = grown_radius(reach);
          if ((a_.spheres()[i].center - cb).squaredNorm() > grown * grown) continue;
          const ClosestPoints d = triangle_triangle_distance(ta, tb);
          if (d.distance > request_.padding) continue;
          record(ta, tb, i, j, &d);
        }
        if (done()) return;
      }
    }
  }

  void record(const Triangle& ta, const Triangle& tb, std::int32_t i, std::int32_t j, const ClosestPoints* d) {
    result_.collision = true;
    if (request_.max_contacts == 0) return;
    MeshContact c;
    c.triangle_a = a_.triangle_id(i);
    c.triangle_b = b_.triangle_id(j);
    if (d != nullptr && d->distance > 0.0) {  // within padding, apart
      c.position = pose_a_ * (0.5 * (d->on_a + d->on_b));
      c.normal = pose_a_.R * (d->on_a - d->on_b).normalized();
    } else {
      c.position = pose_a_ * intersection_point(ta, tb);
      c.normal = pose_a_.R * unit_normal(tb);
      c.depth = std::min(penetration_behind(ta, tb), penetration_behind(tb, ta));
    }
    result_.contacts.push_back(c);
  }

  // b's volumes in a's frame, per thread, valid where stamp equals the query counter.
  struct CarryCache {
    std::vector<BV> carried;
    std::vector<std::uint64_t> stamp;
    std::uint64_t query = 0;
  };
  CarryCache* cache_ = nullptr;
  const Bvh<BV>& a_;
  const Bvh<BV>& b_;
  const Transform& pose_a_;
  const RelativeFrame frame_;
  const CollisionRequest& request_;
  CollisionResult& result_;
};

// Is some component of `inner` (pose relative to `outer`'s frame: inner_in_outer) inside the
// closed mesh `outer`? Returns the contained point in outer's frame.
template <class BV>
bool component_inside(const Bvh<BV>& outer, const Bvh<BV>& inner, const Transform& inner_in_outer,
                      QueryStats& stats, Vec3* where) {
  if (!outer.closed() || outer.empty()) return false;
  for (const Vec3& p : inner.component_points()) {
    const Vec3 q = inner_in_outer * p;
    ++stats.volume_tests;
    if (!contains(outer.root().volume, q)) continue;
    if (contains_point(outer, q, &stats)) {
      *where = q;
      return true;
    }
  }
  return false;
}

// ----------------------------------------------------------------------------------- distance

template <class BV>
class DistanceTraversal {
 public:
  DistanceTraversal(const Bvh<BV>& a, const Bvh<BV>& b, const Transform& b_in_a, double tolerance,
                    double upper_bound, DistanceResult& result)
      : a_(a), b_(b), frame_(RelativeFrame::from(b_in_a)), tolerance_(tolerance), result_(result), best_(upper_bound) {}

  // Best-first (best_first_pair): the first leaf pairs reached are close to the answer, and the
  // bound prunes the most.
  void run() {
    best_first_pair(
        a_, b_, [this](std::int32_t i, std::int32_t j) { return bound(i, j); },
        [this](const BvhNode<BV>& na, const BvhNode<BV>& nb) {
          leaf_pair(na, nb);
          return best_ == 0.0;
        },
        [this] { return best_ - tolerance_; });
    result_.distance = result_.triangle_a >= 0 ? best_ : std::numeric_limits<double>::infinity();
  }

 private:
  double bound(std::int32_t i, std::int32_t j) {
    ++result_.stats.volume_tests;
    return distance_lower_bound(a_.nodes()[i].volume, b_.nodes()[j].volume, frame_);
  }

  void leaf_pair(const BvhNode<BV>& na, const BvhNode<BV>& nb) {
    for (std::int32_t j = nb.first; j < nb.first + nb.count; ++j) {
      const Triangle tb = carried(b_.triangles()[j], frame_);
      const Vec3 cb = frame_.apply(b_.spheres()[j].center);
      const double rb = b_.spheres()[j].radius;
      for (std::int32_t i = na.first; i < na.first + na.count; ++i) {
        // Bounding spheres of the two triangles: most pairs end here.
        const double apart = (a_.spheres()[i].center - cb).norm(), ra = a_.spheres()[i].radius;
        const double lb = apart - ra - rb - kVolumeMargin * (apart + ra + rb);
        if (lb >= best_ - tolerance_) continue;
        ++result_.stats.primitive_tests;
        const ClosestPoints d = triangle_triangle_distance(a_.triangles()[i], tb);
        if (d.distance < best_) {
          best_ = d.distance;
          result_.point_a = d.on_a;
          result_.point_b = d.on_b;
          result_.triangle_a = a_.triangle_id(i);
          result_.triangle_b = b_.triangle_id(j);
          if (best_ == 0.0) return;
        }
      }
    }
  }

  const Bvh<BV>& a_;
  const Bvh<BV>& b_;
  const RelativeFrame frame_;
  const double tolerance_;
  DistanceResult& result_;
  double best_ = std::numeric_limits<double>::infinity();
};

// ---------------------------------------------------------------------------- ray crossings

enum class Crossing { kNone, kProper, kOnSurface, kDegenerate };

// How the segment q -> far meets closed triangle t, exactly. A proper crossing's `sign` is +1
// when q is on the triangle's positive side (det[t1 - t0, t2 - t0, q - t0] < 0), else -1.
Crossing classify_crossing(const Vec3& q, const Vec3& far, const Triangle& t, int& sign) {
  const int sq = detail::orient3d_filtered(t[0], t[1], t[2], q);
  sign = sq;
  const int sf = detail::orient3d_filtered(t[0], t[1], t[2], far);
  if (sq * sf > 0) return Crossing::kNone;
  if (sq == 0) {
    return segment_intersects_triangle(q, q, t[0], t[1], t[2]) ? Crossing::kOnSurface : Crossing::kNone;
  }
  const int o1 = detail::orient3d_filtered(q, far, t[0], t[1]);
  const int o2 = detail::orient3d_filtered(q, far, t[1], t[2]);
  const int o3 = detail::orient3d_filtered(q, far, t[2], t[0]);
  const bool positive = o1 >= 0 && o2 >= 0 && o3 >= 0, negative = o1 <= 0 && o2 <= 0 && o3 <= 0;
  if (!positive && !negative) return Crossing::kNone;
  if (sf == 0 || o1 == 0 || o2 == 0 || o3 == 0) return Crossing::kDegenerate;  // grazes an edge
  return Crossing::kProper;
}

// A lower bound on the distance from q (the mesh frame) to anything in the node: its circumscribed
// sphere's, and for an OBB the box's own (tighter where the box is thin: a point beside a long
// edge run is not kept waiting for every box whose sphere reaches it), less the box's rounding.
template <class BV>
double point_node_bound(const BvhNode<BV>& node, const Vec3& q) {
  return (q - center(node.volume)).norm() - node.size;
}
template <>
double point_node_bound(const BvhNode<Obb>& node, const Vec3& q) {
  const Vec3 offset = q - node.volume.center;
  const double sphere = offset.norm() - node.size;
  if (sphere <= 0.0) {
    const Vec3 local = node.volume.axes.transpose() * offset;
    const double box = (local.cwiseAbs() - node.volume.half).cwiseMax(0.0).norm();
    return box - kVolumeMargin * (offset.norm() + node.volume.radius) - kVolumeMargin;
  }
  return sphere;
}

// point_node_bound clamped at 0 and squared, for a yes/no question at radius r (cutoff r^2):
// a node farther than its circumscribed sphere by `reach` (>= r) is pruned without a square
// root; only a node near enough pays for its box's distance.
template <class BV>
double point_node_bound_squared(const BvhNode<BV>& node, const Vec3& q, double /*reach*/) {
  const double d = std::max(0.0, point_node_bound(node, q));
  return d * d;
}
template <>
double point_node_bound_squared(const BvhNode<Obb>& node, const Vec3& q, double reach) {
  const Vec3 offset = q - node.volume.center;
  const double far = offset.squaredNorm(), sphere = node.size + reach;
  if (far > sphere * sphere) return far;  // |offset| - size > reach: the sphere bound prunes it
  // |offset| <= size + reach here, so this margin is at least point_node_bound's.
  const double margin = kVolumeMargin * (2.0 * node.size + reach) + kVolumeMargin;
  const Vec3 local = node.volume.axes.transpose() * offset;
  const double d = std::max(0.0, std::sqrt((local.cwiseAbs() - node.volume.half).cwiseMax(0.0).squaredNorm()) - margin);
  return d * d;
}

// The surface around a point, by exact ray crossings: on it, or the winding number of the first
// ray that grazes no edge (none decided: every ray grazed one).
struct Winding {
  bool on_surface = false, decided = false;
  int number = 0;
};

template <class BV>
Winding wind(const Bvh<BV>& bvh, const Vec3& point, QueryStats& s) {
  Winding w;
  const BV& root = bvh.root().volume;
  const double reach = 2.0 * (radius(root) + (point - center(root)).norm()) + 1.0;
  // Directions with no simple rational relation to axis-aligned geometry.
  static const Vec3 kDirections[] = {{0.5773, 0.5774, 0.5775}, {-0.8017, 0.2672, 0.5345},
                                     {0.2357, -0.9428, 0.2357}, {0.6247, 0.4685, -0.6247},
                                     {-0.3015, -0.3015, -0.9045}, {0.9701, -0.1213, 0.2091}};
  for (const Vec3& dir : kDirections) {
    const Vec3 far = point + reach * dir.normalized();
    const Ray ray(point, far - point, 1.0);
    int winding = 0;  // signed crossings: the winding number of the surface around the point
    bool degenerate = false;
    auto visit = [&](const BvhNode<BV>& n) {
      ++s.volume_tests;
      return ray_hits(n.volume, ray) ? Visit::kEnter : Visit::kSkip;
    };
    depth_first(bvh, visit, [&](const BvhNode<BV>& n) {
      for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
        ++s.primitive_tests;
        int sign = 0;
        const Crossing c = classify_crossing(point, far, bvh.triangles()[i], sign);
        w.on_surface = c == Crossing::kOnSurface;
        degenerate = c == Crossing::kDegenerate;
        if (w.on_surface || degenerate) return true;  // decided, or this ray cannot decide
        if (c == Crossing::kProper) winding += sign;
      }
      return false;
    });
    if (w.on_surface) return w;
    if (!degenerate) return {false, true, winding};
  }
  return w;
}

}  // namespace

template <class BV>
bool contains_point(const Bvh<BV>& bvh, const Vec3& point, QueryStats* stats) {
  if (bvh.empty()) return false;
  QueryStats local;
  const Winding w = wind(bvh, point, stats ? *stats : local);
  if (w.on_surface) return true;
  // A closed, consistently oriented surface winds an integer number of times around each point
  // not on it: 0 outside, +-1 inside one shell, 2 where two shells overlap (parity would call
  // that outside). A cavity's inward shell cancels its outer one.
  if (w.decided) return bvh.closed() && w.number != 0;
  return bvh.closed();  // every ray grazed an edge: err towards "inside" (never a false negative)
}

template <class BV>
std::optional<int> winding_number(const Bvh<BV>& bvh, const Vec3& point, QueryStats* stats) {
  if (bvh.empty() || !bvh.closed()) return std::nullopt;
  QueryStats local;
  const Winding w = wind(bvh, point, stats ? *stats : local);
  if (w.on_surface || !w.decided) return std::nullopt;
  return w.number;
}

std::optional<int> signed_crossing(const Vec3& a, const Vec3& b, const Triangle& t) {
  int sign = 0;
  switch (classify_crossing(a, b, t, sign)) {
    case Crossing::kNone: return 0;
    case Crossing::kProper: return sign;
    case Crossing::kOnSurface:
    case Crossing::kDegenerate: break;
  }
  return std::nullopt;
}

template <class BV>
CollisionResult collide(const Bvh<BV>& a, const Transform& pose_a, const Bvh<BV>& b, const Transform& pose_b,
                        const CollisionRequest& request) {
  CollisionResult result;
  if (a.empty() || b.empty()) return result;
  CollisionTraversal<BV>(a, b, pose_a, pose_b, request, result).run();
  if (result.collision || !request.solids) return result;
  // No surfaces within reach: one solid may still hold the other.
  const Transform b_in_a = relative_transform(pose_a, pose_b);
  Vec3 where;
  const bool b_in_a_solid = component_inside(a, b, b_in_a, result.stats, &where);
  if (b_in_a_solid) where = pose_a * where;
  const bool a_in_b_solid = !b_in_a_solid && component_inside(b, a, relative_transform(pose_b, pose_a), result.stats, &where);
  if (a_in_b_solid) where = pose_b * where;
  if (b_in_a_solid || a_in_b_solid) {
    result.collision = true;
    if (request.max_contacts > 0) {
      MeshContact c;
      c.position = where;
      result.contacts.push_back(c);
    }
  }
  return result;
}

template <class BV>
DistanceResult distance(const Bvh<BV>& a, const Transform& pose_a, const Bvh<BV>& b, const Transform& pose_b,
                        const DistanceRequest& request) {
  DistanceResult result;
  if (a.empty() || b.empty()) return result;
  const Transform b_in_a = relative_transform(pose_a, pose_b);
  DistanceTraversal<BV>(a, b, b_in_a, request.tolerance, request.upper_bound, result).run();
  if (result.distance > 0.0 && request.solids) {
    // Solids: a component wholly inside the other mesh is at distance 0.
    Vec3 where;  // in a's frame
    bool inside = component_inside(a, b, b_in_a, result.stats, &where);
    if (!inside && component_inside(b, a, relative_transform(pose_b, pose_a), result.stats, &where)) {
      where = b_in_a * where;  // found in b's frame
      inside = true;
    }
    if (inside) {
      result.distance = 0.0;
      result.point_a = result.point_b = where;
      result.triangle_a = result.triangle_b = -1;
    }
  }
  result.point_a = pose_a * result.point_a;
  result.point_b = pose_a * result.point_b;
  return result;
}

template <class BV>
DistanceResult point_distance(const Bvh<BV>& bvh, const Transform& pose, const Vec3& p, double upper_bound) {
  DistanceResult result;
  result.point_a = p;
  if (bvh.empty()) return result;
  const Vec3 q = pose.R.transpose() * (p - pose.t);  // the point in the mesh frame
  double best = upper_bound;
  auto bound = [&](std::int32_t n) {
    ++result.stats.volume_tests;
    return point_node_bound(bvh.nodes()[n], q);
  };
  auto leaf = [&](const BvhNode<BV>& n) {
    for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
      ++result.stats.primitive_tests;
      const Triangle& t = bvh.triangles()[i];
      if (triangle_plane_beyond(q, t[0], t[1], t[2], best)) continue;
      const Vec3 c = closest_point_on_triangle(q, t[0], t[1], t[2]);
      const double d = (c - q).norm();
      if (d < best) {
        best = d;
        result.distance = d;
        result.point_b = pose * c;
        result.triangle_b = bvh.triangle_id(i);
      }
    }
    return false;
  };
  nearest_first(bvh, bound, leaf, [&] { return best; });
  return result;
}

// Calls found(i) for triangles i (in bvh.triangles()) closer than `radius` to q (the mesh's frame),
// nearest subtrees first, until it returns true. (reach: the radius with room for the rounding of
// a squared norm against a norm.)
template <class BV, class Found>
void walk_within(const Bvh<BV>& bvh, const Vec3& q, double radius, QueryStats& s, Found&& found) {
  const double reach = radius * (1.0 + 1e-9) + kVolumeMargin, cutoff = radius * radius;
  auto bound = [&](std::int32_t n) {
    ++s.volume_tests;
    return point_node_bound_squared(bvh.nodes()[n], q, reach);
  };
  auto leaf = [&](const BvhNode<BV>& n) {
    for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
      ++s.primitive_tests;
      const Triangle& t = bvh.triangles()[i];
      if (triangle_plane_beyond(q, t[0], t[1], t[2], radius)) continue;
      if ((closest_point_on_triangle(q, t[0], t[1], t[2]) - q).norm() < radius && found(i)) return true;
    }
    return false;
  };
  nearest_first(bvh, bound, leaf, [&] { return cutoff; });
}

template <class BV>
bool point_within(const Bvh<BV>& bvh, const Transform& pose, const Vec3& p, double radius, QueryStats* stats) {
  if (bvh.empty() || !(radius > 0.0)) return false;
  QueryStats local;
  bool near = false;
  walk_within(bvh, Vec3(pose.R.transpose() * (p - pose.t)), radius, stats ? *stats : local,
              [&](std::int32_t) { return near = true; });
  return near;
}

template <class BV>
bool triangles_near(const Bvh<BV>& bvh, const Vec3& p, double radius, std::size_t max_count,
                    std::vector<std::int32_t>& out, QueryStats* stats) {
  if (bvh.empty() || !(radius > 0.0)) return true;
  QueryStats local;
  std::size_t found = 0;
  walk_within(bvh, p, radius, stats ? *stats : local, [&](std::int32_t i) {
    out.push_back(i);
    return ++found > max_count;
  });
  return found <= max_count;
}

template <class BV>
RayHit raycast(const Bvh<BV>& bvh, const Transform& pose, const Vec3& origin, const Vec3& direction,
               double max_range, bool any_hit, QueryStats* stats) {
  RayHit hit;
  const double len = direction.norm();
  if (bvh.empty() || !(len > 0.0)) return hit;
  QueryStats local;
  QueryStats& s = stats ? *stats : local;
  const Vec3 o = pose.R.transpose() * (origin - pose.t);
  const Vec3 d = pose.R.transpose() * (direction / len);
  double best = max_range > 0.0 ? max_range : std::numeric_limits<double>::max();
  auto visit = [&](const BvhNode<BV>& n) {
    ++s.volume_tests;
    return ray_hits(n.volume, Ray(o, d, best)) ? Visit::kEnter : Visit::kSkip;
  };
  depth_first(bvh, visit, [&](const BvhNode<BV>& n) {
    for (std::int32_t i = n.first; i < n.first + n.count; ++i) {
      ++s.primitive_tests;
      const Triangle& t = bvh.triangles()[i];
      // Moller-Trumbore, with the hit accepted on the closed triangle.
      const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0], p = d.cross(e2);
      const double det = e1.dot(p);
      if (det == 0.0) continue;
      const Vec3 r = o - t[0];
      const double u = r.dot(p) / det, qv = d.dot(r.cross(e1)) / det;
      const double dist = e2.dot(r.cross(e1)) / det;
      if (u < 0.0 || qv < 0.0 || u + qv > 1.0 || dist < 0.0 || dist > best) continue;
      best = dist;
      hit.hit = true;
      hit.distance = dist;
      hit.triangle = bvh.triangle_id(i);
      if (any_hit) return true;
    }
    return false;
  });
  if (hit.hit) hit.point = origin + hit.distance * (direction / len);
  return hit;
}

#define BVH_COLLISION_INSTANTIATE_QUERIES(BV)                                                          \
  template CollisionResult collide<BV>(const Bvh<BV>&, const Transform&, const Bvh<BV>&, const Transform&, \
                                       const CollisionRequest&);                                       \
  template DistanceResult distance<BV>(const Bvh<BV>&, const Transform&, const Bvh<BV>&, const Transform&, \
                                       const DistanceRequest&);                                        \
  template RayHit raycast<BV>(const Bvh<BV>&, const Transform&, const Vec3&, const Vec3&, double, bool,   \
                              QueryStats*);                                                            \
  template bool contains_point<BV>(const Bvh<BV>&, const Vec3&, QueryStats*);                         \
  template std::optional<int> winding_number<BV>(const Bvh<BV>&, const Vec3&, QueryStats*);            \
  template DistanceResult point_distance<BV>(const Bvh<BV>&, const Transform&, const Vec3&, double);   \
  template bool point_within<BV>(const Bvh<BV>&, const Transform&, const Vec3&, double, QueryStats*);     \
  template bool triangles_near<BV>(const Bvh<BV>&, const Vec3&, double, std::size_t, std::vector<std::int32_t>&, \
                                   QueryStats*);

BVH_COLLISION_INSTANTIATE_QUERIES(Aabb)
BVH_COLLISION_INSTANTIATE_QUERIES(Obb)
BVH_COLLISION_INSTANTIATE_QUERIES(Sphere)
BVH_COLLISION_INSTANTIATE_QUERIES(Kdop14)
BVH_COLLISION_INSTANTIATE_QUERIES(Kdop18)
BVH_COLLISION_INSTANTIATE_QUERIES(Kdop26)
BVH_COLLISION_INSTANTIATE_QUERIES(Rss)

}  // namespace bvh_collision
