#include "bvh_collision/model/robot_collision_model.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <map>
#include <numeric>
#include <optional>

#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/thread_pool.h"
#include "bvh_collision/narrowphase/shape_queries.h"

namespace bvh_collision {
namespace {

// A sphere in the link frame that holds every shape of the link.
LinkBound bounding_sphere(const std::vector<BodyShape>& shapes) {
  Aabb box;
  for (const BodyShape& s : shapes) extend_by_shape(s, box);
  const Vec3 c = center(box);
  double r = 0.0;
  for (const BodyShape& s : shapes) r = std::max(r, shape_reach(s, c));
  return {c, grown_radius(r)};
}

}  // namespace

std::vector<BodyShape> RobotCollisionModel::placed_shapes(int link) const {
  std::vector<BodyShape> out;
  for (const LinkShape& s : shapes_[static_cast<std::size_t>(link)]) out.push_back({ref(s), s.origin});
  return out;
}

RobotCollisionModel::RobotCollisionModel(RobotModel robot, AllowedCollisionMatrix acm, const CheckerOptions& options)
    : robot_(std::move(robot)),
      acm_(std::move(acm)),
      limits_(options.limits),
      default_padding_(options.padding),
      link_padding_(options.link_padding) {
  const std::size_t n = robot_.links().size();
  robot_links_ = n;
  check_limit("robot '" + robot_.name() + "' with its links", double(n), limits_.robot_links, "max_robot_links");
  if (acm_.size() != n) acm_ = AllowedCollisionMatrix(n);
  padding_.resize(n, options.padding);
  for (std::size_t l = 0; l < n; ++l) {
    if (const auto it = options.link_padding.find(robot_.links()[l].name); it != options.link_padding.end()) {
      padding_[l] = it->second;
    }
  }
  // The pairs to check. Every link with geometry gets its BVH: environment queries check links
  // that no self pair needs.
  std::vector<bool> needed(n, false);
  for (std::size_t a = 0; a < n; ++a) {
    needed[a] = !robot_.links()[a].collision.empty();
    for (std::size_t b = a + 1; b < n; ++b) {
      if (robot_.links()[a].collision.empty() || robot_.links()[b].collision.empty() || acm_.allowed(a, b)) continue;
      checked_pairs_.emplace_back(static_cast<int>(a), static_cast<int>(b));
      // Before any hierarchy is built: refusing such a robot must cost nothing.
      if (checked_pairs_.size() > limits_.checked_pairs) {
        throw LimitExceeded("robot '" + robot_.name() + "' with its checked link pairs (more than the limit: counting "
                            "stopped at " + std::to_string(checked_pairs_.size()) + ")", double(checked_pairs_.size()),
                            limits_.checked_pairs, "max_checked_pairs");
      }
    }
  }
  build_shapes(options, needed);
  kinematics_ = KinematicsPlan(robot_, needed);
  compute_motion_rates();
}

// Exact primitives stay primitives; each distinct mesh gets one hierarchy and one hull, shared by
// the elements that use it.
void RobotCollisionModel::build_shapes(const CheckerOptions& options, const std::vector<bool>& needed) {
  const std::size_t n = robot_.links().size();
  shapes_.resize(n);
  bounds_.resize(n);
  std::map<const TriangleMesh*, int> index;
  std::vector<const TriangleMesh*> distinct;
  for (std::size_t l = 0; l < n; ++l) {
    if (!needed[l]) continue;
    for (const CollisionElement& e : robot_.links()[l].collision) {
      LinkShape s;
      s.origin = e.origin;
      if (e.shape == CollisionElement::Shape::kSphere) {
        s.primitive = Primitive::sphere(e.radius);
      } else if (e.shape == CollisionElement::Shape::kCylinder) {
        s.primitive = Primitive::cylinder(e.radius, e.length);
      } else {
        const auto [it, fresh] = index.emplace(e.mesh.get(), static_cast<int>(distinct.size()));
        if (fresh) distinct.push_back(e.mesh.get());
        s.mesh = it->second;
      }
      shapes_[l].push_back(s);
    }
  }
  build_meshes(distinct, options.bvh);
  for (std::size_t l = 0; l < n; ++l) {
    if (needed[l]) bounds_[l] = bounding_sphere(placed_shapes(static_cast<int>(l)));
  }
}

// The hierarchies and hulls are independent jobs: they share the pool's threads, largest mesh
// first (a robot comes up in about the time of its largest mesh, not the sum of all of them).
void RobotCollisionModel::build_meshes(const std::vector<const TriangleMesh*>& distinct, const BuildOptions& bvh) {
  std::vector<std::optional<Bvh<Obb>>> trees(distinct.size());
  std::vector<std::optional<ConvexHull>> hulls(distinct.size());
  std::vector<std::size_t> jobs(2 * distinct.size());  // 2m: mesh m's hierarchy, 2m + 1: its hull
  std::iota(jobs.begin(), jobs.end(), 0);
  std::stable_sort(jobs.begin(), jobs.end(), [&](std::size_t a, std::size_t b) {
    return distinct[a / 2]->triangles.size() > distinct[b / 2]->triangles.size();
  });
  std::atomic<std::size_t> next{0};
  ThreadPool::shared().run(static_cast<unsigned>(jobs.size()), [&](unsigned) {
    for (std::size_t k = next++; k < jobs.size(); k = next++) {
      const std::size_t m = jobs[k] / 2;
      if (jobs[k] % 2 == 0) {
        trees[m].emplace(Bvh<Obb>::build(*distinct[m], bvh));
      } else {  // surface vertices only: a hull vertex is taken to lie on the mesh (meshes_distance)
        hulls[m].emplace(convex_hull(used_vertices(*distinct[m])));
      }
    }
  });
  for (std::size_t m = 0; m < distinct.size(); ++m) {
    meshes_.push_back(std::move(*trees[m]));
    hulls_.push_back(std::move(*hulls[m]));
  }
}

RobotCollisionModel RobotCollisionModel::carrying(const std::vector<AttachedBody>& bodies,
                                                  const NamedAllowedCollisions& allowed) const {
  RobotCollisionModel out = *this;
  for (const AttachedBody& body : bodies) out.add_body(body, allowed);
  std::vector<bool> needed(out.shapes_.size());
  for (std::size_t l = 0; l < needed.size(); ++l) needed[l] = !out.shapes_[l].empty();
  out.kinematics_ = KinematicsPlan(out.robot_, needed);
  out.compute_motion_rates();
  return out;
}

// One carried body: a link of its own (shapes, bound, padding) and its self pairs.
void RobotCollisionModel::add_body(const AttachedBody& body, const NamedAllowedCollisions& allowed) {
  const std::string what = "attached object '" + body.id + "'";
  const int parent = robot_.link_index(body.link);
  if (parent < 0) throw std::invalid_argument(what + ": no link '" + body.link + "'");
  if (robot_.link_index(body.id) >= 0) throw std::invalid_argument(what + ": the robot has a link of that name");
  if (body.shapes.empty()) throw std::invalid_argument(what + " has no shapes");
  std::vector<bool> touches(robot_.links().size(), false);
  touches[static_cast<std::size_t>(parent)] = true;
  for (const std::string& name : body.touch_links) {
    const int l = robot_.link_index(name);
    if (l < 0) throw std::invalid_argument(what + ": no touch link '" + name + "'");
    touches[static_cast<std::size_t>(l)] = true;
  }
  robot_ = robot_.with_fixed_link(body.id, parent, Transform::Identity());
  const std::size_t n = robot_.links().size();
  check_limit("robot '" + robot_.name() + "' with its links and carried objects", double(n), limits_.robot_links, "max_robot_links");
  const int self = static_cast<int>(n) - 1;
  acm_ = acm_.grown_to(n);
  std::vector<LinkShape> shapes;
  for (const CollisionObject& o : body.shapes) {
    LinkShape s;
    s.origin = o.pose;
    s.mesh = append_shape(shape_of(o), meshes_, hulls_);
    s.primitive = o.primitive;
    shapes.push_back(s);
  }
  shapes_.push_back(std::move(shapes));
  bounds_.push_back(bounding_sphere(placed_shapes(self)));
  const auto named = link_padding_.find(body.id);
  padding_.push_back(named != link_padding_.end() ? named->second : default_padding_);
  for (int l = 0; l < self; ++l) {
    if (shapes_[static_cast<std::size_t>(l)].empty() || (l < static_cast<int>(touches.size()) && touches[l]) ||
        allowed.allowed(body.id, robot_.links()[static_cast<std::size_t>(l)].name)) {
      acm_.allow(l, self, AcmReason::kAdjacent);
      continue;
    }
    checked_pairs_.emplace_back(l, self);
  }
  check_limit("robot '" + robot_.name() + "' with its checked pairs and carried objects", double(checked_pairs_.size()),
              limits_.checked_pairs, "max_checked_pairs");
}

// For each link, walk to the root: a revolute joint moves the link's points at most at their
// distance from the joint's origin per radian, which is bounded by the sum of the joint offsets
// below it plus the link's geometry reach (the chain's length, whatever the other joints do);
// a prismatic joint moves them at 1 m per metre and lengthens the chain by its largest travel
// within its source variable's limits (link_speed widens the bound for values beyond them).
void RobotCollisionModel::compute_motion_rates() {
  const auto& links = robot_.links();
  const auto& joints = robot_.joints();
  std::vector<double> travel(robot_.variable_count(), 0.0);  // largest |value| within limits
  for (const RobotJoint& joint : joints) {
    if (joint.variable >= 0) travel[joint.variable] = std::max(std::abs(joint.lower), std::abs(joint.upper));
  }
  motion_rates_.assign(links.size(), std::vector<double>(robot_.variable_count(), 0.0));
  motion_turns_.assign(links.size(), std::vector<double>(robot_.variable_count(), 0.0));
  motion_slides_.assign(links.size(), {});
  reach_ = 0.0;
  for (std::size_t l = 0; l < links.size(); ++l) {
    if (bounds_[l].radius < 0.0) continue;
    double reach = bounds_[l].center.norm() + bounds_[l].radius + padding_[l];
    for (int j = links[l].parent_joint; j >= 0; j = links[joints[j].parent_link].parent_joint) {
      const RobotJoint& joint = joints[j];
      int variable = joint.variable;
      double multiplier = 1.0, offset = 0.0;
      if (joint.mimic >= 0) {
        variable = joints[joint.mimic].variable;
        multiplier = std::abs(joint.multiplier);
        offset = std::abs(joint.offset);
      }
      if (variable >= 0 && (joint.type == JointType::kRevolute || joint.type == JointType::kContinuous)) {
        motion_rates_[l][variable] += multiplier * reach;
        motion_turns_[l][variable] += multiplier;
      } else if (variable >= 0 && joint.type == JointType::kPrismatic) {
        motion_rates_[l][variable] += multiplier;
        reach += multiplier * travel[variable] + offset;
        motion_slides_[l].push_back({variable, multiplier, travel[variable]});
      }
      reach += joint.origin.t.norm();
    }
    reach_ = std::max(reach_, reach);
  }
  motion_terms_.assign(links.size(), {});
  for (std::size_t l = 0; l < links.size(); ++l) {
    for (std::size_t v = 0; v < motion_rates_[l].size(); ++v) {
      if (motion_rates_[l][v] != 0.0 || motion_turns_[l][v] != 0.0) {
        motion_terms_[l].push_back({static_cast<int>(v), motion_rates_[l][v], motion_turns_[l][v]});
      }
    }
  }
}

}  // namespace bvh_collision
