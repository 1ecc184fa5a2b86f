#include "bvh_collision/geometry/convex_hull.h"
#include "bvh_collision/geometry/detail/filtered_predicates.h"

#include <algorithm>
#include <random>
#include <cmath>
#include <cstdint>
#include <limits>

#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision {
namespace {

using Face = std::array<int, 3>;

bool lexicographic_less(const Vec3& a, const Vec3& b) {
  return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
}

// Four points spanning a volume, found greedily (far apart, then off the line, then off the
// plane), each choice confirmed by an exact predicate. False when the points are coplanar.
bool initial_tetrahedron(const std::vector<Vec3>& p, std::array<int, 4>& t) {
  t = {0, 0, 0, 0};
  double best = -1.0;
  for (std::size_t i = 1; i < p.size(); ++i) {
    if (const double d = (p[i] - p[0]).squaredNorm(); d > best) best = d, t[1] = static_cast<int>(i);
  }
  best = -1.0;
  t[2] = -1;
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double d = (p[i] - p[0]).cross(p[t[1]] - p[0]).squaredNorm();
    if (d > best && projection_axis(p[0], p[t[1]], p[i]) >= 0) best = d, t[2] = static_cast<int>(i);
  }
  if (t[2] < 0) return false;  // collinear
  best = -1.0;
  t[3] = -1;
  const Vec3 normal = (p[t[1]] - p[0]).cross(p[t[2]] - p[0]);
  for (std::size_t i = 1; i < p.size(); ++i) {
    const double d = std::abs(normal.dot(p[i] - p[0]));
    if (d > best && detail::orient3d_filtered(p[0], p[t[1]], p[t[2]], p[i]) != 0) best = d, t[3] = static_cast<int>(i);
  }
  return t[3] >= 0;
}

// Randomized incremental hull with exact signs (Clarkson and Shor 1989; the outside sets of
// Quickhull, Barber, Dobkin and Huhdanpaa 1996): every point outside the hull so far waits in
// the outside set of one face it sees. Points are added in a fixed pseudo-random order: the faces
// a point sees (a connected set, found from its face across edges) are replaced by a cone to
// their horizon, and their waiting points go to the first new face each one sees (one that sees
// no new face is inside the new hull: above a replaced face and below every cone face means
// within the cone). Expected O(n log n) for any input; inserting every point against every face
// (what this replaced) was O(n^2): 200,000 points on a sphere took minutes.
class Quickhull {
 public:
  explicit Quickhull(const std::vector<Vec3>& p) : p_(p), face_of_(p.size(), -1), cone_from_(p.size(), -1), cone_to_(p.size(), -1) {}

  std::uint64_t tests() const { return tests_; }

  std::vector<Face> run(const std::array<int, 4>& t) {
    for (int k = 0; k < 4; ++k) {  // each face oriented away from the fourth vertex
      Face f{t[k], t[(k + 1) % 4], t[(k + 2) % 4]};
      if (detail::orient3d_filtered(p_[f[0]], p_[f[1]], p_[f[2]], p_[t[(k + 3) % 4]]) < 0) std::swap(f[1], f[2]);
      faces_.push_back({f, {-1, -1, -1}, true, {}});
    }
    // The tetrahedron's neighbours: the face holding each edge reversed.
    for (int a = 0; a < 4; ++a) {
      for (int k = 0; k < 3; ++k) {
        for (int b = 0; b < 4; ++b) {
          for (int j = 0; j < 3; ++j) {
            if (faces_[b].v[j] == faces_[a].v[(k + 1) % 3] && faces_[b].v[(j + 1) % 3] == faces_[a].v[k]) faces_[a].n[k] = b;
          }
        }
      }
    }
    std::vector<int> rest;
    for (int i = 0; i < static_cast<int>(p_.size()); ++i) {
      if (std::find(t.begin(), t.end(), i) == t.end()) rest.push_back(i);
    }
    assign(rest, 0);
    // A fixed permutation (the same hull for the same input, run after run).
    std::mt19937_64 shuffle(0x9e3779b97f4a7c15ULL ^ p_.size());
    std::shuffle(rest.begin(), rest.end(), shuffle);
    for (const int q : rest) {
      if (face_of_[q] >= 0) add_point(q);  // else inside the hull by now
    }
    std::vector<Face> out;
    for (const FaceRec& f : faces_) {
      if (f.alive) out.push_back(f.v);
    }
    return out;
  }

 private:
  struct FaceRec {
    Face v;
    std::array<int, 3> n;  // the face across edge v[k] -> v[k + 1]
    bool alive = true;
    std::vector<int> outside;  // points that see this face (strictly), waiting
  };

  bool sees(int face, int point) const {
    const Face& v = faces_[face].v;
    ++tests_;
    return detail::orient3d_filtered(p_[v[0]], p_[v[1]], p_[v[2]], p_[point]) < 0;
  }

  // Each point to the first face from `first` on that it sees; the others are inside.
  void assign(const std::vector<int>& points, int first) {
    for (const int q : points) {
      face_of_[q] = -1;
      for (int f = first; f < static_cast<int>(faces_.size()); ++f) {
        if (faces_[f].alive && sees(f, q)) {
          faces_[f].outside.push_back(q);
          face_of_[q] = f;
          break;
        }
      }
    }
  }

  // The faces the eye sees, from its own face across edges (a face is tested once per step);
  // the horizon: edges (u, w) of seen faces whose neighbour h is not seen, at h's edge j.
  void find_visible(int eye) {
    ++step_;
    if (mark_.size() < faces_.size()) mark_.resize(2 * faces_.size(), {0, 0});
    const int face = face_of_[eye];
    visible_.assign(1, face);
    stack_.assign(1, face);
    mark_[face] = {step_, 1};
    horizon_.clear();
    while (!stack_.empty()) {
      const int g = stack_.back();
      stack_.pop_back();
      for (int k = 0; k < 3; ++k) {
        const int h = faces_[g].n[k];
        if (mark_[h].first != step_) {
          mark_[h] = {step_, sees(h, eye) ? 1 : 2};
          if (mark_[h].second == 1) visible_.push_back(h), stack_.push_back(h);
        }
        if (mark_[h].second == 2) {
          const FaceRec& hidden = faces_[h];
          const int j = hidden.n[0] == g ? 0 : hidden.n[1] == g ? 1 : 2;
          horizon_.push_back({faces_[g].v[k], faces_[g].v[(k + 1) % 3], h, j});
        }
      }
    }
  }

  // The point `eye`, outside the hull: the faces it sees replaced by a cone to their horizon.
  void add_point(int eye) {
    find_visible(eye);
    orphans_.clear();
    for (const int g : visible_) {
      FaceRec& rec = faces_[g];
      rec.alive = false;
      for (const int q : rec.outside) {
        if (q != eye) orphans_.push_back(q);
      }
      std::vector<int>().swap(rec.outside);
    }
    face_of_[eye] = -1;
    // One face (u, w, eye) per horizon edge: across (u, w) the hidden face, across (w, eye) the
    // cone face that starts at w, across (eye, u) the one that ends at u (the horizon is a cycle).
    const int first = static_cast<int>(faces_.size());
    for (const HorizonEdge& e : horizon_) {
      const int f = static_cast<int>(faces_.size());
      faces_.push_back({{e.u, e.w, eye}, {e.hidden, -1, -1}, true, {}});
      faces_[e.hidden].n[e.hidden_edge] = f;
      cone_from_[e.u] = f;
      cone_to_[e.w] = f;
    }
    for (int f = first; f < static_cast<int>(faces_.size()); ++f) {
      faces_[f].n[1] = cone_from_[faces_[f].v[1]];
      faces_[f].n[2] = cone_to_[faces_[f].v[0]];
    }
    assign(orphans_, first);
  }

  struct HorizonEdge {
    int u, w, hidden, hidden_edge;
  };

  const std::vector<Vec3>& p_;
  std::vector<FaceRec> faces_;
  std::vector<int> face_of_;             // per point: the face whose outside set holds it, or -1
  std::vector<int> cone_from_, cone_to_;  // per horizon vertex: the cone face starting / ending there
  // Scratch of add_point, kept between steps.
  std::uint64_t step_ = 0;
  std::vector<std::pair<std::uint64_t, int>> mark_;  // per face: the step it was last met in, and how
  std::vector<int> visible_, stack_, orphans_;
  mutable std::uint64_t tests_ = 0;  // the hull's work: O(n log n) expected, n^2 was minutes
  std::vector<HorizonEdge> horizon_;
};

// Hulls with fewer vertices are searched whole: a climb's bookkeeping costs more than it saves.
constexpr std::size_t kClimbFrom = 32;

// The faces' edges, each once per end, and the axis extremes (hull_support).
void index_edges(ConvexHull& hull) {
  const std::size_t n = hull.vertices.size();
  std::vector<std::vector<std::uint32_t>> around(n);
  for (const auto& f : hull.faces) {
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      around[a].push_back(static_cast<std::uint32_t>(b));  // (each edge in two faces: both ends get it)
    }
  }
  hull.neighbour_start.assign(1, 0);
  for (std::vector<std::uint32_t>& list : around) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
    hull.neighbours.insert(hull.neighbours.end(), list.begin(), list.end());
    hull.neighbour_start.push_back(static_cast<std::uint32_t>(hull.neighbours.size()));
  }
  for (int axis = 0; axis < 3; ++axis) {
    int lo = 0, hi = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (hull.vertices[i][axis] < hull.vertices[lo][axis]) lo = static_cast<int>(i);
      if (hull.vertices[i][axis] > hull.vertices[hi][axis]) hi = static_cast<int>(i);
    }
    hull.extremes[2 * axis] = lo;
    hull.extremes[2 * axis + 1] = hi;
  }
}

}  // namespace

ConvexHull convex_hull(const std::vector<Vec3>& points) {
  std::vector<Vec3> p;
  p.reserve(points.size());
  for (const Vec3& x : points) {
    if (x.allFinite()) p.push_back(x);
  }
  std::sort(p.begin(), p.end(), lexicographic_less);
  p.erase(std::unique(p.begin(), p.end()), p.end());
  ConvexHull hull;
  std::array<int, 4> t;
  for (const Vec3& x : p) hull.extent = std::max(hull.extent, x.norm());
  if (p.size() < 4 || !initial_tetrahedron(p, t)) {
    hull.vertices = p;
    return hull;
  }
  Quickhull quickhull(p);
  std::vector<Face> faces = quickhull.run(t);
  hull.orientation_tests = quickhull.tests();
  std::vector<int> index(p.size(), -1);
  for (Face& f : faces) {
    for (int& v : f) {
      if (index[v] < 0) {
        index[v] = static_cast<int>(hull.vertices.size());
        hull.vertices.push_back(p[v]);
      }
      v = index[v];
    }
  }
  hull.faces = std::move(faces);
  index_edges(hull);
  return hull;
}

namespace {

// A climb stalled at `at`: some neighbour is level with it within `rounding`. On a convex polytope
// every vertex that is not furthest along d has an edge that truly rises, so a path of rising
// edges leads from `at` to a furthest vertex, every vertex of it no lower than `at` (so computed
// no lower than here - 2 rounding). The vertices reachable from `at` through such vertices hold
// that path: the search spreads over them (a flat face, not the hull) and either meets a vertex
// higher than `at` by more than the rounding, where the climb goes on (-1 and `at` moved), or
// answers the highest it met, as high as the furthest of all within the rounding.
int search_level(const ConvexHull& hull, const Vec3& d, int& at, double rounding, std::size_t* work) {
  thread_local std::vector<std::uint32_t> seen;  // per vertex: the search that last met it
  thread_local std::uint32_t search = 0;
  thread_local std::vector<int> queue;
  const std::vector<Vec3>& v = hull.vertices;
  if (seen.size() < v.size()) seen.assign(v.size(), 0), search = 0;
  if (++search == 0) std::fill(seen.begin(), seen.end(), 0), search = 1;
  const double here = d.dot(v[at]);
  queue.assign(1, at);
  seen[at] = search;
  int best = at;
  double best_dot = here;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    const int u = queue[q];
    for (std::uint32_t k = hull.neighbour_start[u]; k < hull.neighbour_start[u + 1]; ++k) {
      const std::uint32_t w = hull.neighbours[k];
      if (seen[w] == search) continue;
      seen[w] = search;
      const double x = d.dot(v[w]);
      if (work != nullptr) ++*work;
      if (x > here + rounding) {
        at = static_cast<int>(w);
        return -1;
      }
      if (x < here - 2.0 * rounding) continue;
      if (x > best_dot) best_dot = x, best = static_cast<int>(w);
      queue.push_back(static_cast<int>(w));
    }
  }
  return best;
}

}  // namespace

int hull_support(const ConvexHull& hull, const Vec3& d, int from, std::size_t* work) {
  const std::vector<Vec3>& v = hull.vertices;
  if (v.size() < kClimbFrom || hull.neighbours.empty()) {
    int best = 0;
    double best_dot = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (const double x = d.dot(v[i]); x > best_dot) best_dot = x, best = static_cast<int>(i);
    }
    if (work != nullptr) *work += v.size();
    return best;
  }
  int at = from;
  if (at < 0 || static_cast<std::size_t>(at) >= v.size()) {
    at = hull.extremes[d.x() >= 0 ? 1 : 0];
    for (const int e : {d.y() >= 0 ? hull.extremes[3] : hull.extremes[2], d.z() >= 0 ? hull.extremes[5] : hull.extremes[4]}) {
      if (d.dot(v[e]) > d.dot(v[at])) at = e;
    }
  }
  // Each dot product is within 3 ulps of |d|_1 * extent of its value: a neighbour higher by more
  // than this is truly higher.
  const double rounding = 1e-13 * d.cwiseAbs().sum() * hull.extent;
  for (;;) {
    const double here = d.dot(v[at]);
    int next = -1;
    double next_dot = here, nearest = -std::numeric_limits<double>::infinity();
    for (std::uint32_t k = hull.neighbour_start[at]; k < hull.neighbour_start[at + 1]; ++k) {
      const double x = d.dot(v[hull.neighbours[k]]);
      nearest = std::max(nearest, x);
      if (x > next_dot) next_dot = x, next = static_cast<int>(hull.neighbours[k]);
    }
    if (work != nullptr) *work += hull.neighbour_start[at + 1] - hull.neighbour_start[at];
    if (next >= 0 && next_dot > here + rounding) {
      at = next;
      continue;
    }
    if (nearest < here - rounding) return at;
    if (const int best = search_level(hull, d, at, rounding, work); best >= 0) return best;
  }
}

}  // namespace bvh_collision
