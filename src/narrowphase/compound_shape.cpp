#include "bvh_collision/narrowphase/compound_shape.h"

#include <algorithm>
#include <limits>

#include "bvh_collision/narrowphase/shape_queries.h"

namespace bvh_collision {
namespace {

// Any part of `a` against a counterpart `meets(shape, pose, contacts)`: contacts gathered up to
// request.max_contacts, the walk stopped at a hit once none are wanted.
template <typename Meets>
bool any_part(const CompoundShape& a, const Transform& pa, const PairRequest& request, std::vector<MeshContact>* contacts,
              Meets&& meets) {
  const std::size_t first = contacts != nullptr ? contacts->size() : 0;
  auto want = [&] { return contacts != nullptr && contacts->size() - first < request.max_contacts; };
  bool hit = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const bool wanted = want();
    if (meets(a.ref(i), pa * a.part(i).origin, wanted ? contacts : nullptr)) {
      hit = true;
      if (!want()) break;
    }
  }
  if (contacts != nullptr) contacts->resize(std::min(contacts->size(), first + request.max_contacts));
  return hit;
}

// The nearest part of `a` to a counterpart `distance(shape, pose, best, wa, wb)`.
template <typename Distance>
double nearest_part(const CompoundShape& a, const Transform& pa, double best, Vec3& wa, Vec3& wb, Distance&& distance) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    Vec3 ta = Vec3::Zero(), tb = Vec3::Zero();
    const double d = distance(a.ref(i), pa * a.part(i).origin, best, ta, tb);
    if (d < best) {
      best = d;
      wa = ta;
      wb = tb;
    }
  }
  return best;
}

}  // namespace

bool compound_collides(const CompoundShape& a, const Transform& pa, const ShapeRef& b, const Transform& pb,
                       const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  return any_part(a, pa, request, contacts, [&](const ShapeRef& s, const Transform& ps, std::vector<MeshContact>* c) {
    return shapes_collide(s, ps, b, pb, request, c, stats);
  });
}

bool compounds_collide(const CompoundShape& a, const Transform& pa, const CompoundShape& b, const Transform& pb,
                       const PairRequest& request, std::vector<MeshContact>* contacts, QueryStats& stats) {
  return any_part(a, pa, request, contacts, [&](const ShapeRef& s, const Transform& ps, std::vector<MeshContact>* c) {
    // The inner walk gathers what is still wanted of the whole.
    PairRequest inner = request;
    if (c != nullptr) inner.max_contacts = request.max_contacts - std::min(request.max_contacts, c->size());
    return any_part(b, pb, inner, c, [&](const ShapeRef& t, const Transform& pt, std::vector<MeshContact>* ct) {
      return shapes_collide(s, ps, t, pt, request, ct, stats);
    });
  });
}

double compound_distance(const CompoundShape& a, const Transform& pa, const ShapeRef& b, const Transform& pb, double best,
                         bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  return nearest_part(a, pa, best, wa, wb, [&](const ShapeRef& s, const Transform& ps, double below, Vec3& ta, Vec3& tb) {
    return shapes_distance(s, ps, b, pb, below, solids, ta, tb, stats, tolerance);
  });
}

double compounds_distance(const CompoundShape& a, const Transform& pa, const CompoundShape& b, const Transform& pb,
                          double best, bool solids, Vec3& wa, Vec3& wb, QueryStats& stats, double tolerance) {
  return nearest_part(a, pa, best, wa, wb, [&](const ShapeRef& s, const Transform& ps, double below, Vec3& ta, Vec3& tb) {
    return nearest_part(b, pb, below, tb, ta, [&](const ShapeRef& t, const Transform& pt, double below_t, Vec3& ub, Vec3& ua) {
      return shapes_distance(s, ps, t, pt, below_t, solids, ua, ub, stats, tolerance);
    });
  });
}

bool compound_meets_octree(const CompoundShape& a, const Transform& pa, const Octree& tree, const PairRequest& request,
                           OctreeContact* contact, QueryStats& stats) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (shape_meets_octree(a.ref(i), pa * a.part(i).origin, tree, request, contact, stats)) return true;
  }
  return false;
}

OctreeDistance compound_octree_distance(const CompoundShape& a, const Transform& pa, const Octree& tree, bool solids,
                                        double upper_bound, QueryStats& stats) {
  OctreeDistance best;
  best.distance = upper_bound;
  bool found = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const OctreeDistance d = shape_octree_distance(a.ref(i), pa * a.part(i).origin, tree, solids, best.distance, stats);
    if (d.distance < best.distance) best = d, found = true;
  }
  if (!found) best.distance = std::numeric_limits<double>::infinity();
  return best;
}

bool compound_holds_point(const CompoundShape& a, const Transform& pa, const Vec3& p, double padding) {
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (shape_holds_point(a.ref(i), pa * a.part(i).origin, p, padding)) return true;
  }
  return false;
}

double compound_ray_entry(const CompoundShape& a, const Transform& pa, const Vec3& origin, const Vec3& unit, double length) {
  double first = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < a.size(); ++i) {
    first = std::min(first, shape_ray_entry(a.ref(i), pa * a.part(i).origin, origin, unit, std::min(first, length)));
  }
  return first;
}

}  // namespace bvh_collision
