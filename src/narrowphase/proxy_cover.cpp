// The proven covers of a link proxy (proxy_build.h; the proof is told in link_proxy.h): by cubes
// for a curved primitive, by surface pieces and cubes for a shape bounded by triangles.
#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>

#include "bvh_collision/geometry/distance.h"
#include "proxy_build.h"
#include "proxy_build_index.h"

namespace bvh_collision {
namespace proxy_build {

// The point of the primitive's surface nearest p (p inside the primitive, its frame).
Vec3 nearest_surface_point(const Primitive& prim, const Vec3& p) {
  switch (prim.kind) {
    case Primitive::Kind::kMesh: break;  // not a primitive
    case Primitive::Kind::kSphere: return p.norm() > 0.0 ? Vec3(p * (prim.radius / p.norm())) : Vec3(prim.radius, 0, 0);
    case Primitive::Kind::kBox: {
      int axis = 0;
      (prim.half - p.cwiseAbs()).minCoeff(&axis);
      Vec3 q = p;
      q[axis] = p[axis] < 0.0 ? -prim.half[axis] : prim.half[axis];
      return q;
    }
    case Primitive::Kind::kCylinder: {
      const double rho = p.head<2>().norm();
      if (prim.half_length - std::abs(p.z()) < prim.radius - rho) {
        return Vec3(p.x(), p.y(), p.z() < 0.0 ? -prim.half_length : prim.half_length);
      }
      return rho > 0.0 ? Vec3(p.x() * prim.radius / rho, p.y() * prim.radius / rho, p.z()) : Vec3(prim.radius, 0, p.z());
    }
    case Primitive::Kind::kCapsule: {
      const Vec3 axis(0.0, 0.0, std::clamp(p.z(), -prim.half_length, prim.half_length));
      const Vec3 off = p - axis;
      return off.norm() > 0.0 ? Vec3(axis + off * (prim.radius / off.norm())) : Vec3(axis + Vec3(prim.radius, 0, 0));
    }
    case Primitive::Kind::kCone: {
      const double h = prim.half_length, slope = prim.radius / std::max(2.0 * h, 1e-300);
      const double rho = p.head<2>().norm(), cos_a = 1.0 / std::sqrt(1.0 + slope * slope);
      const double slant = (slope * (h - p.z()) - rho) * cos_a;
      if (p.z() + h <= slant) return Vec3(p.x(), p.y(), -h);
      // Out along the slant's normal (rho, z) ~ (1, slope) in the half plane through p.
      const Vec3 radial = rho > 0.0 ? Vec3(p.x() / rho, p.y() / rho, 0.0) : Vec3(1.0, 0.0, 0.0);
      return p + slant * cos_a * (radial + Vec3(0.0, 0.0, slope));
    }
  }
  return p;
}

namespace {

// The cover of one shape (see link_proxy.h): cubes from the shape's box down, largest first. A
// cube that holds no point of the link is dropped; one inside a sphere already chosen is done;
// otherwise the largest proven sphere that contains it is chosen (an interior sphere of radius
// depth + e/2, centred on the inward normal through the surface point nearest the cube), or,
// for a cube small enough, its own ball; else the cube is split.
class ShapeCover {
 public:
  ShapeCover(const ShapeField& field, double half_level) : field_(field), half_level_(half_level), index_(2.05 * half_level) {}

  void run(const Vec3& center, double half_edge) {
    std::vector<std::pair<Vec3, double>> level{{center, half_edge}}, next;
    for (int depth = 0; !level.empty(); ++depth) {
      if (depth > kMaxDepth) throw std::logic_error("link proxy: no cube small enough for the level");
      next.clear();
      for (const auto& [c, a] : level) {
        if (!cell(c, a)) {
          for (int k = 0; k < 8; ++k) {
            const Vec3 offset((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
            next.emplace_back(c + a * offset, 0.5 * a);
          }
        }
      }
      std::swap(level, next);
    }
  }
  const std::vector<Chosen>& chosen() const { return chosen_; }

 private:
  // Settles the cube (true) or asks for it to be split (false).
  bool cell(const Vec3& c, double half_edge) {
    const double h = grown_radius(half_edge * std::sqrt(3.0));
    ++field_.stats->cubes;
    const bool held = index_.any_near(c, h, [&](const SphereGrid::Entry& s) {
      ++field_.stats->sphere_tests;
      return (s.centre - c).norm() + h <= s.radius * (1.0 - kVolumeMargin);
    });
    if (held) return true;
    const bool in = field_.solid() && field_.inside(c);
    Vec3 nearest;
    const double limit = 4.0 * h + 8.0 * half_level_;
    const double d = field_.surface_distance(c, in, limit, &nearest);
    if (!in && low(d) > h) return true;  // no point of the link in this cube
    if (field_.solid() && d < limit && try_interior(c, h, in, d, nearest)) return true;
    if (high(d) + h <= half_level_) return choose(c, h);  // every point within d + h <= e/2 of the link
    if (in && h <= low(d) + half_level_) return choose(c, low(d) + half_level_);
    return false;
  }
  // The interior spheres on the normal through the nearest surface point, largest first.
  bool try_interior(const Vec3& c, double h, bool in, double d, const Vec3& nearest) {
    if (!(d > 0.0) && !in) return false;
    Vec3 inward = in ? Vec3(c - nearest) : Vec3(nearest - c);
    if (inward.norm() == 0.0) return false;
    inward.normalize();
    for (double t = 16.0 * (h + half_level_); t >= 0.25 * half_level_; t *= 0.5) {
      const Vec3 center = nearest + t * inward;
      if (!field_.inside(center)) continue;
      const double depth = low(field_.surface_distance(center, true, 2.0 * t + h, nullptr));
      const double radius = depth + half_level_;
      if ((center - c).norm() + h <= radius * (1.0 - kVolumeMargin)) return choose(center, radius);
    }
    return false;
  }
  double low(double d) const { return d * (1.0 - kVolumeMargin) - kVolumeMargin; }
  double high(double d) const { return grown_radius(d) + kVolumeMargin; }
  bool choose(const Vec3& c, double radius) {
    index_.insert(static_cast<std::uint32_t>(chosen_.size()), c, radius);
    chosen_.push_back({c, radius});
    return true;
  }

  const ShapeField& field_;
  double half_level_;
  std::vector<Chosen> chosen_;
  SphereGrid index_;  // chosen_ by position
};

// The cover of a shape whose boundary is triangles (a mesh, a box), proven on its surface and,
// for a solid, in its volume (see link_proxy.h):
//   surface: every triangle lies, with margin delta, inside one chosen sphere (all three corners
//     within radius - delta: the triangle then by convexity), after splitting it in four as often
//     as needed; a piece that no sphere holds gets a sphere of its own. Every point within delta
//     of the surface is then covered. An open mesh is only its surface: done.
//   volume: cubes from the box down; a cube inside one chosen sphere is done, one with no point
//     of the solid is dropped, one whose points all lie within delta of the surface (d + h <
//     delta) is done by the surface step, one deep inside gets the interior sphere at its centre;
//     the others are split.
class PolyhedralCover {
  struct Cube {
    Vec3 center;
    double half_edge;
    std::int32_t parent;  // in split_, the cube it was split from
  };
  struct SplitCube {
    Vec3 center;
    std::int8_t in;                // its centre in the solid: -1 not yet asked, 0 no, 1 yes
    bool wound;                    // whether `winding` is known
    std::int32_t winding;          // the surface's winding number around its centre
    std::uint32_t begin, end;      // in lists_, the spheres of the cover's start that meet it
    bool kept;                     // whether the mesh's triangles near it were kept (few enough):
    std::uint32_t near_begin, near_end;  // in near_, those within 2 h + delta of its centre, nearest first
  };
  // Triangles kept per split cube at most: more, and its cubes ask the mesh's BVH.
  static constexpr std::size_t kMaxKept = 64;
  // A kept triangle: its index in the mesh's BVH and its distance from the split cube's centre.
  struct NearTriangle {
    std::int32_t triangle;
    double distance;
  };

 public:
  PolyhedralCover(const ShapeField& field, double half_level, std::vector<Chosen> seed)
      : field_(field), half_level_(half_level), delta_(0.125 * half_level), chosen_(std::move(seed)),
        builder_(field, half_level), added_(2.05 * half_level) {
    for (const Chosen& s : chosen_) held_r2_.push_back(reach_squared(s.radius));
  }

  void run() {
    // The surface: a sphere that holds a piece may hold part of the piece it was split from, so
    // each piece asks the seed's spheres that may hold part of its parent (from a k-d tree of their centres for a whole
    // triangle) and those added since (their own index).
    std::vector<Vec3> centres;
    double largest = 0.0;
    for (const Chosen& s : chosen_) centres.push_back(s.center), largest = std::max(largest, s.radius);
    const PointTree seeds(centres);
    for (const Triangle& t : field_.faces) {
      const Piece whole = piece(t[0], t[1], t[2]);
      seeds.in_ball(whole.centre, whole.radius + largest, [&](std::uint32_t i) {
        if (may_hold(chosen_[i], whole)) piece_lists_.push_back(i);
      });
      surface(t[0], t[1], t[2], 0, 0);
      piece_lists_.clear();
    }
    if (!field_.solid()) return;  // an open mesh is its surface: nothing inside to cover
    added_ = SphereGrid(2.05 * half_level_);  // what the surface added is in every cube's list
    // The volume: a sphere that holds a cube meets the cube it was split from, so each cube asks
    // only the spheres that met its parent (a list that shrinks with the cubes) and those added
    // since the volume began (their own index): the same answer as asking all of them.
    const auto [center, half] = field_.box();
    std::vector<Cube> level{{center, half.maxCoeff() * (1.0 + 1e-9) + 1e-12, -1}}, next;
    std::vector<SplitCube> next_split;
    std::vector<std::uint32_t> next_lists;
    std::vector<NearTriangle> next_near;
    start_ = chosen_.size();
    lists_.resize(start_);
    std::iota(lists_.begin(), lists_.end(), 0u);
    // The first cube's "parent" is itself, with every sphere (and no triangles kept).
    split_.push_back({center, -1, false, 0, 0, static_cast<std::uint32_t>(start_), false, 0, 0});
    level.front().parent = 0;
    for (int depth = 0; !level.empty(); ++depth) {
      if (depth > kMaxDepth) throw std::logic_error("link proxy: no cube small enough for the level");
      next.clear(), next_split.clear(), next_lists.clear(), next_near.clear();
      for (const Cube& q : level) {
        if (cube(q)) continue;
        const SplitCube& from = split_[static_cast<std::size_t>(q.parent)];
        const auto begin = static_cast<std::uint32_t>(next_lists.size());
        const double reach = grown_radius(q.half_edge * std::sqrt(3.0));
        for (std::uint32_t k = from.begin; k < from.end; ++k) {
          const Chosen& s = chosen_[lists_[k]];
          const double r = grown_radius(s.radius + reach);
          if ((s.center - q.center).squaredNorm() <= r * r) next_lists.push_back(lists_[k]);
        }
        const auto parent = static_cast<std::int32_t>(next_split.size());
        const auto near_begin = static_cast<std::uint32_t>(next_near.size());
        const bool kept = keep_near(q, from, next_near);
        next_split.push_back({q.center, cube_in_, false, 0, begin, static_cast<std::uint32_t>(next_lists.size()), kept, near_begin,
                              static_cast<std::uint32_t>(next_near.size())});
        carry_winding(q, from, next_split.back());
        for (int k = 0; k < 8; ++k) {
          const Vec3 offset((k & 1) ? 0.5 : -0.5, (k & 2) ? 0.5 : -0.5, (k & 4) ? 0.5 : -0.5);
          next.push_back({q.center + q.half_edge * offset, 0.5 * q.half_edge, parent});
        }
      }
      std::swap(level, next), std::swap(split_, next_split), std::swap(lists_, next_lists), std::swap(near_, next_near);
    }
  }
  const std::vector<Chosen>& chosen() const { return chosen_; }

 private:
  static bool holds(const Vec3& centre, double radius, const Vec3& p, double margin) {
    const double r = (radius - margin) * (1.0 - kVolumeMargin) - kVolumeMargin;
    return r > 0.0 && (p - centre).squaredNorm() <= r * r;
  }
  static bool holds(const Chosen& s, const Vec3& p, double margin) { return holds(s.center, s.radius, p, margin); }
  // Candidate lists this short are not filtered for a piece's parts: filtering costs more than the
  // tests it saves.
  static constexpr std::size_t kShortList = 8;
  // A surface piece's bounding ball (centroid, farthest corner).
  struct Piece {
    Vec3 centre;
    double radius;
  };
  static Piece piece(const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 g = (a + b + c) / 3.0;
    return {g, grown_radius(std::sqrt(std::max({(a - g).squaredNorm(), (b - g).squaredNorm(), (c - g).squaredNorm()})))};
  }
  // Whether the sphere may hold some part of the piece with the margin delta: it then holds a point
  // of the piece, within the piece's radius of its centroid, delta inside its own radius.
  bool may_hold(const Chosen& s, const Piece& p) const {
    if (!(s.radius > delta_)) return false;
    const double r = grown_radius(s.radius - delta_ + p.radius);
    return (s.center - p.centre).squaredNorm() <= r * r;
  }
  // Whether one sphere holds the piece a b c, with the margin delta: its parent's spheres (from
  // piece_lists_[begin]) and those added since the seed.
  bool held(const Vec3& a, const Vec3& b, const Vec3& c, std::size_t begin) {
    ++field_.stats->sphere_tests;
    // (holds(s, p, delta_) for the three corners, with the sphere's reach at delta_ kept squared.)
    auto all = [&](const Vec3& o, double r2) {
      return (a - o).squaredNorm() <= r2 && (b - o).squaredNorm() <= r2 && (c - o).squaredNorm() <= r2;
    };
    if (last_ < chosen_.size() && all(chosen_[last_].center, held_r2_[last_])) return true;
    for (std::size_t k = begin; k < piece_lists_.size(); ++k) {
      ++field_.stats->sphere_tests;
      const std::uint32_t s = piece_lists_[k];
      if (all(chosen_[s].center, held_r2_[s])) return last_ = s, true;
    }
    return added_.any_near(a, delta_, [&](const SphereGrid::Entry& s) {  // (the entry's own values: no other read)
      ++field_.stats->sphere_tests;
      return all(s.centre, reach_squared(s.radius)) ? (last_ = s.id, true) : false;
    });
  }
  // holds(s, p, delta_) is |p - s.center|^2 <= this (negative where the reach is not positive).
  double reach_squared(double radius) const {
    const double r = (radius - delta_) * (1.0 - kVolumeMargin) - kVolumeMargin;
    return r > 0.0 ? r * r : -1.0;
  }
  void add(const Chosen& s) {
    added_.insert(static_cast<std::uint32_t>(chosen_.size()), s.center, s.radius);
    chosen_.push_back(s);
    held_r2_.push_back(reach_squared(s.radius));
  }
  // The piece a b c, whose candidate spheres are piece_lists_[begin, end()).
  void surface(const Vec3& a, const Vec3& b, const Vec3& c, int depth, std::size_t begin) {
    ++field_.stats->surface_pieces;
    if (held(a, b, c, begin)) return;
    const double edge = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (edge > delta_ && depth < kMaxDepth) {
      const Vec3 ab = 0.5 * (a + b), bc = 0.5 * (b + c), ca = 0.5 * (c + a);
      const std::array<std::array<Vec3, 3>, 4> parts{{{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}}};
      const std::size_t end = piece_lists_.size();
      for (const auto& [p, q, r] : parts) {
        if (end - begin <= kShortList) {  // a short list serves the parts as it is (any superset does)
          surface(p, q, r, depth + 1, begin);
          continue;
        }
        const Piece part = piece(p, q, r);
        for (std::size_t k = begin; k < end; ++k) {
          if (may_hold(chosen_[piece_lists_[k]], part)) piece_lists_.push_back(piece_lists_[k]);
        }
        surface(p, q, r, depth + 1, end);
        piece_lists_.resize(end);
      }
      return;
    }
    // A piece no sphere holds: the interior sphere touching it at its centroid, if that holds it,
    // else the ball of radius e/2 around the centroid (a surface point: within e/2 of the link).
    const Vec3 g = (a + b + c) / 3.0;
    const Vec3 normal = (b - a).cross(c - a);
    if (field_.solid() && normal.norm() > 0.0) {
      if (auto s = builder_.medial_sphere(g, -normal.normalized(), 2.0 * field_.box().second.maxCoeff())) {
        if (holds(*s, a, delta_) && holds(*s, b, delta_) && holds(*s, c, delta_)) {
          add(*s);
          return;
        }
      }
    }
    add({g, half_level_ * (1.0 - kVolumeMargin) - kVolumeMargin});
    if (!held(a, b, c, begin)) throw std::logic_error("link proxy: a surface piece larger than the level");
  }
  // Settles the cube (true) or asks for it to be split (false; cube_in_ then says which side
  // of the surface its centre is on, when that was asked: -1 unknown, 0 out, 1 in).
  bool cube(const Cube& q) {
    ++field_.stats->cubes;
    cube_in_ = -1;
    const Vec3& c = q.center;
    const double h = grown_radius(q.half_edge * std::sqrt(3.0));
    ++field_.stats->sphere_tests;
    if (last_cube_ < chosen_.size() && holds(chosen_[last_cube_], c, h)) return true;
    const SplitCube& from = split_[static_cast<std::size_t>(q.parent)];
    for (std::uint32_t k = from.begin; k < from.end; ++k) {
      ++field_.stats->sphere_tests;
      if (holds(chosen_[lists_[k]], c, h)) return last_cube_ = lists_[k], true;
    }
    const bool held_cube = added_.any_near(c, h, [&](const SphereGrid::Entry& s) {
      ++field_.stats->sphere_tests;
      return holds(s.centre, s.radius, c, h) ? (last_cube_ = s.id, true) : false;
    });
    if (held_cube) return true;
    // Only a surface farther than h settles a cube larger than delta (it is then dropped or given
    // an interior sphere): "is the surface closer than `beyond`?" decides it, and d_low(beyond) > h.
    const double beyond = grown_radius(grown_radius(h));
    if (field_.mesh == nullptr) cube_in_ = field_.inside(c) ? 1 : 0;
    double d = beyond;  // >= beyond, unless asked exactly below
    bool exact = false;
    if (h < delta_) {
      d = surface_near(q, std::max(beyond, delta_), false);
      exact = d < std::max(beyond, delta_);
    } else if (surface_near(q, beyond, true) < beyond) {
      return false;
    }
    const double d_low = d * (1.0 - kVolumeMargin) - kVolumeMargin, d_high = grown_radius(d) + kVolumeMargin;
    if (d_low > h && cube_in_ < 0) cube_in_ = side_of(q) ? 1 : 0;
    if (d_low > h && cube_in_ == 0) return true;       // no point of the solid here
    if (exact && d_high + h < delta_) return true;     // every point within delta of the surface
    if (d_low > h && cube_in_ == 1 && h <= half_level_) {  // deep enough: the interior sphere at c holds it
      const double depth = field_.surface_distance(c, true, 4.0 * h + 8.0 * half_level_, nullptr);
      add({c, depth * (1.0 - kVolumeMargin) - kVolumeMargin + half_level_});
      return true;
    }
    return false;
  }
  // The distance from the cube's centre to the surface when below `limit` (else `limit`), as
  // ShapeField::surface_distance answers; with `first`, any distance below the limit once one is
  // found. From the triangles its parent kept when it did: they are all that come that close.
  double surface_near(const Cube& q, double limit, bool first) {
    const SplitCube& from = split_[static_cast<std::size_t>(q.parent)];
    const bool in = cube_in_ == 1;
    if (!from.kept) {
      if (first) return field_.within(q.center, in, limit) ? 0.0 : limit;
      return field_.surface_distance(q.center, in, limit, nullptr);
    }
    ++field_.stats->distance_queries;
    const double offset = grown_radius(q.half_edge * std::sqrt(3.0));  // from the parent's centre, at most
    double best = limit;
    for (std::uint32_t k = from.near_begin; k < from.near_end && !beyond(near_[k], offset, limit); ++k) {
      ++field_.stats->triangle_tests;
      const Triangle& t = field_.mesh->triangles()[static_cast<std::size_t>(near_[k].triangle)];
      if (triangle_plane_beyond(q.center, t[0], t[1], t[2], best)) continue;
      const double d = (closest_point_on_triangle(q.center, t[0], t[1], t[2]) - q.center).norm();
      if (d < best) {
        best = d;
        if (first) break;
      }
    }
    return best;
  }
  // Whether a kept triangle, and every one after it (they are kept nearest first), is at least
  // `limit` from a point `offset` or less from the centre it was measured from: its distance
  // less the offset, less the rounding of both distances.
  static bool beyond(const NearTriangle& t, double offset, double limit) {
    return t.distance * (1.0 - kVolumeMargin) - kVolumeMargin - offset >= grown_radius(limit);
  }
  // Keeps, for the cube being split, the mesh's triangles within kept_reach of its centre (from
  // its parent's when those were kept); whether they were few enough. A child asks for the
  // surface within max(its beyond, delta) <= h/2 + delta of its centre, h/2 from this centre, and
  // keeps those within h + delta of its own, inside the 2 h + delta kept here.
  bool keep_near(const Cube& q, const SplitCube& from, std::vector<NearTriangle>& out) {
    if (field_.mesh == nullptr) return false;  // a box: its own distance is cheap
    const double reach = 2.0 * grown_radius(q.half_edge * std::sqrt(3.0)) + delta_;
    const std::size_t begin = out.size();
    auto keep = [&](std::int32_t triangle) {
      ++field_.stats->triangle_tests;
      const Triangle& t = field_.mesh->triangles()[static_cast<std::size_t>(triangle)];
      if (triangle_plane_beyond(q.center, t[0], t[1], t[2], reach)) return;
      const double d = (closest_point_on_triangle(q.center, t[0], t[1], t[2]) - q.center).norm();
      if (d < reach) out.push_back({triangle, d});
    };
    if (!from.kept) {
      ++field_.stats->distance_queries;
      QueryStats walk;
      found_.clear();
      const bool few = triangles_near(*field_.mesh, q.center, reach, kMaxKept, found_, &walk);
      field_.stats->bvh_volume_tests += walk.volume_tests;
      if (!few) return false;
      for (const std::int32_t t : found_) keep(t);
    } else {
      const double offset = grown_radius(q.half_edge * std::sqrt(3.0));  // from the parent's centre, at most
      for (std::uint32_t k = from.near_begin; k < from.near_end && !beyond(near_[k], offset, reach); ++k) keep(near_[k].triangle);
    }
    std::sort(out.begin() + static_cast<std::ptrdiff_t>(begin), out.end(),
              [](const NearTriangle& a, const NearTriangle& b) { return a.distance < b.distance; });
    return true;
  }
  // Whether the centre of a cube that the surface does not reach (d > h) is in the solid. The
  // centre of the cube it was split from is one of its corners, so no surface lies between the
  // two: that cube's answer, asked once for its eight (the first cube is its own parent).
  bool side_of(const Cube& q) {
    SplitCube& parent = split_[static_cast<std::size_t>(q.parent)];
    if (parent.in >= 0) return parent.in == 1;
    if (field_.mesh != nullptr) {
      if (const std::optional<int> w = field_.winding(parent.center)) {
        parent.wound = true, parent.winding = *w, parent.in = *w != 0 ? 1 : 0;
        return parent.in == 1;
      }
    }
    parent.in = field_.inside(parent.center) ? 1 : 0;
    return parent.in == 1;
  }
  // The winding number around a split cube's centre from its parent's, by the crossings of the
  // segment between them (a corner of the cube to its centre): every triangle it can cross is
  // among the parent's kept ones. A segment that grazes an edge or ends on the surface leaves it
  // unknown (a ray cast asks, if a cube needs it).
  void carry_winding(const Cube& q, const SplitCube& from, SplitCube& out) const {
    if (field_.mesh == nullptr || !from.wound || !from.kept) return;
    std::int32_t w = from.winding;
    for (std::uint32_t k = from.near_begin; k < from.near_end; ++k) {
      const std::optional<int> crossing =
          signed_crossing(from.center, q.center, field_.mesh->triangles()[static_cast<std::size_t>(near_[k].triangle)]);
      if (!crossing) return;
      w -= *crossing;
    }
    out.wound = true, out.winding = w, out.in = w != 0 ? 1 : 0;
  }

  const ShapeField& field_;
  double half_level_, delta_;
  std::vector<Chosen> chosen_;
  std::vector<double> held_r2_;  // per chosen sphere: reach_squared
  SeedBuilder builder_;
  SphereGrid added_;  // those added since the lists in use were made (the seed's, the volume's), by position
  std::vector<std::uint32_t> piece_lists_;  // the surface pieces' candidate spheres, a stack of ranges
  std::size_t start_ = 0;  // spheres when the volume began
  std::size_t last_ = 0, last_cube_ = 0;
  std::vector<SplitCube> split_;         // the cubes split into this level's, by Cube::parent
  std::vector<std::uint32_t> lists_;     // their spheres, by SplitCube::begin/end
  std::vector<NearTriangle> near_;       // their kept triangles, by SplitCube::near_begin/near_end
  std::vector<std::int32_t> found_;      // a BVH query's triangles (scratch)
  std::int8_t cube_in_ = -1;
};

}  // namespace

std::vector<Chosen> cover_polyhedron(const ShapeField& field, double half_level, std::vector<Chosen> seed) {
  PolyhedralCover cover(field, half_level, std::move(seed));
  cover.run();
  return cover.chosen();
}

std::vector<Chosen> cover_by_cubes(const ShapeField& field, double half_level) {
  ShapeCover cover(field, half_level);
  const auto [center, half] = field.box();
  cover.run(center, half.maxCoeff() * (1.0 + 1e-9) + 1e-12);
  return cover.chosen();
}

}  // namespace proxy_build
}  // namespace bvh_collision
