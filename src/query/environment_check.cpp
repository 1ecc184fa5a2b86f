// CollisionChecker against the environment: links against the octree and the collision objects.
#include <algorithm>

#include "bvh_collision/query/collision_checker.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/narrowphase/proxy_octree.h"
#include "bvh_collision/narrowphase/tolerance_policy.h"

namespace bvh_collision {
namespace {

thread_local std::vector<Transform> tl_env_poses;
thread_local std::vector<std::uint32_t> tl_near_objects;
thread_local std::vector<ObjectBoxTree::Entry> tl_robot_objects;

// Up to this many objects a link tries each in turn; beyond, only those the list's box tree
// finds near the robot and then near the link (the walk over all grows with the scene, the
// tree's with log n).
constexpr std::size_t kObjectsWalkedInTurn = 16;

// A box around a ball, grown by the rounding of its centre.
void ball_box(const Vec3& centre, double reach, Vec3& lo, Vec3& hi) {
  const Vec3 r = Vec3::Constant(reach + pose_margin(centre.norm() + reach));
  lo = centre - r;
  hi = centre + r;
}

// The slots of the objects whose boxes meet the link's box [lo, hi] among those near the robot
// (every object of a small list), ascending: the order the walk over all would try them in.
void objects_near(const ObjectList& objects, const std::vector<ObjectBoxTree::Entry>& near_robot, const Vec3& lo, const Vec3& hi,
                  std::vector<std::uint32_t>& out) {
  out.clear();
  if (objects.size() <= kObjectsWalkedInTurn) {
    for (std::size_t o = 0; o < objects.size(); ++o) out.push_back(static_cast<std::uint32_t>(o));
    return;
  }
  for (const ObjectBoxTree::Entry& e : near_robot) {
    if ((e.lo.array() <= hi.array()).all() && (lo.array() <= e.hi.array()).all()) out.push_back(e.slot);
  }
  std::sort(out.begin(), out.end());
}

}  // namespace

// The objects whose boxes meet the box of every link's ball (grown by its padding; not by the
// tolerance, which adds no obstacle: narrowphase/tolerance_policy.h): one walk of the object
// list's tree a state, each link then filters these.
void CollisionChecker::objects_near_robot(const std::vector<Transform>& poses, const ObjectList& objects,
                                          const std::vector<char>* only, std::vector<ObjectBoxTree::Entry>& out) const {
  out.clear();
  if (objects.size() <= kObjectsWalkedInTurn) return;
  Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (std::size_t l = 0; l < m_->shapes().size(); ++l) {
    if (m_->shapes()[l].empty() || (only != nullptr && !(*only)[l])) continue;
    Vec3 a, b;
    ball_box(poses[l] * m_->bounds()[l].center, m_->bounds()[l].radius + m_->paddings()[l], a, b);
    lo = lo.cwiseMin(a), hi = hi.cwiseMax(b);
  }
  if (!(lo.array() <= hi.array()).all()) return;
  objects.for_each_box_meeting(lo, hi, [&](const ObjectBoxTree::Entry& e) { out.push_back(e); });
}

bool CollisionChecker::link_meets_octree(int link, const Transform& pose, const Octree& tree,
                                         const EnvironmentRequest& request, EnvironmentResult& result) const {
  PairRequest r;
  r.padding = m_->paddings()[link];
  r.tolerance = request.tolerance;
  r.solids = request.solids;
  OctreeContact contact;
  ++result.stats.pair_tests;
  if (!compound_meets_octree(m_->compound(link), pose, tree, r, &contact, result.stats)) return false;
  result.contacts.push_back({link, std::string(), contact.voxel, contact.position});
  return true;
}

bool CollisionChecker::link_meets_object(int link, const Transform& pose, const CollisionObject& object,
                                         const EnvironmentRequest& request, EnvironmentResult& result) const {
  const double padding = m_->paddings()[link];
  const double reach = m_->bounds()[link].radius + object.bound_radius + padding;
  if ((pose * m_->bounds()[link].center - object.pose * object.bound_center).squaredNorm() > reach * reach) return false;
  ++result.stats.pair_tests;
  const ShapeRef obstacle = shape_of(object);
  PairRequest r;
  r.padding = padding;
  r.tolerance = request.tolerance;
  r.max_contacts = 1;
  r.solids = request.solids;
  std::vector<MeshContact> contacts;
  if (!compound_collides(m_->compound(link), pose, obstacle, object.pose, r, &contacts, result.stats)) return false;
  result.contacts.push_back({link, object.id, {}, contacts.empty() ? Vec3(pose.t) : contacts.front().position});
  return true;
}

// (Against objects a sphere walk was slower than the exact path, so objects stay exact:
// docs/performance.md.)
bool CollisionChecker::link_proxy_meets_octree(int link, const Transform& pose, const LinkProxy& proxy, const Octree& tree,
                                               const OctreeDistanceField& field, bool contacts, EnvironmentResult& result) const {
  const ProxyOctreeHit h = proxy_meets_octree(proxy, pose, m_->paddings()[link], tree, field, contacts);
  if (h.contact) result.contacts.push_back({link, std::string(), h.contact->voxel, h.contact->position});
  return h.hit;
}

double CollisionChecker::link_octree_distance(int link, const Transform& pose, const Octree& tree, double best,
                                              bool solids, EnvironmentResult& result) const {
  const OctreeDistance d = compound_octree_distance(m_->compound(link), pose, tree, solids, best, result.stats);
  if (!(d.distance < best)) return best;
  result.min_distance = d.distance;
  result.closest_link = link;
  result.closest_object.clear();
  result.closest_voxel = d.voxel;
  result.point_link = d.on_link;
  result.point_obstacle = d.on_cube;
  return d.distance;
}

double CollisionChecker::link_object_distance(int link, const Transform& pose, const CollisionObject& object,
                                              double best, bool solids, EnvironmentResult& result) const {
  const ShapeRef obstacle = shape_of(object);
  Vec3 wa, wb;
  const double d = compound_distance(m_->compound(link), pose, obstacle, object.pose, best, solids, wa, wb, result.stats);
  if (!(d < best)) return best;
  result.min_distance = d;
  result.closest_link = link;
  result.closest_object = object.id;
  result.point_link = wa;
  result.point_obstacle = wb;
  return d;
}

// The distance field over the robot's reach around its root (RobotCollisionModel::reach: every
// link point of a state within limits), far enough for the largest link bound and padding.
std::shared_ptr<const OctreeDistanceField> CollisionChecker::octree_field(const Environment& env, const Transform& root_pose,
                                                                        bool build) const {
  double cap = 0.0;
  for (std::size_t l = 0; l < m_->bounds().size(); ++l) cap = std::max(cap, m_->bounds()[l].radius + m_->paddings()[l]);
  const Vec3 reach = Vec3::Constant(m_->reach());
  return env.octree_distance_field(root_pose.t - reach, root_pose.t + reach, cap + env.octree().resolution(),
                                   std::size_t(1) << 24, build);
}

EnvironmentResult CollisionChecker::check_environment(const double* state, const Environment& env,
                                                      const EnvironmentRequest& request) const {
  require_carried(env);
  require_finite_state(state, "environment check");
  using Field = EnvironmentRequest::DistanceField;
  const bool use_octree = request.octree && !env.octree().empty();
  const std::shared_ptr<const OctreeDistanceField> field =
      use_octree && request.distance_field != Field::kOff
          ? octree_field(env, request.root_pose, request.distance_field == Field::kBuild)
          : nullptr;
  return environment_check(state, env, request, field.get());
}

EnvironmentResult CollisionChecker::environment_check(const double* state, const Environment& env,
                                                      const EnvironmentRequest& request,
                                                      const OctreeDistanceField* field) const {
  EnvironmentResult result;
  std::vector<Transform>& poses = tl_env_poses;
  m_->kinematics().compute(state, poses);
  if (!is_rigid(request.root_pose)) throw std::invalid_argument("environment check: the root pose is not a finite rigid transform");
  for (std::size_t l = 0; l < m_->shapes().size(); ++l) {
    if (!m_->shapes()[l].empty()) poses[l] = request.root_pose * poses[l];
  }
  const bool use_octree = request.octree && !env.octree().empty();
  const bool stop_early = !request.all_links && !request.distance;
  const std::vector<char>* only = request.only_links;
  // At a tolerance, a boolean check may answer from a link's proxy against the octree
  // (narrowphase/tolerance_policy.h: against an obstacle its error is half its level); a contact
  // is then an occupied cube within padding + level / 2. Only with the distance field: without it
  // a walk of the octree per sphere is slower than the OBB trees (docs/performance.md).
  ToleranceQuestion question{request.tolerance, Counterpart::kOctree};
  question.boolean = !request.distance;
  question.solids = request.solids;
  question.octree_field = field != nullptr;
  const ProxyLevel* proxies = a_->proxies_for(proxy_use(question).decide_up_to);
  std::vector<ObjectBoxTree::Entry>& near_robot = tl_robot_objects;
  if (request.objects) objects_near_robot(poses, env.objects(), only, near_robot);
  for (std::size_t l = 0; l < m_->shapes().size() && !(stop_early && result.collision); ++l) {
    if (m_->shapes()[l].empty() || (only != nullptr && !(*only)[l])) continue;
    const int link = static_cast<int>(l);
    // Cleared: every point of the link is farther than its padding from every occupied cube.
    const LinkBound& bound = m_->bounds()[l];
    const bool cleared = field && field->lower_bound(poses[l] * bound.center) >
                                      grown_radius(bound.radius + m_->paddings()[l]) + pose_margin(poses[l].t.norm() + bound.center.norm());
    bool hit = use_octree && !cleared &&
               (proxies != nullptr ? link_proxy_meets_octree(link, poses[l], proxies->links[l], env.octree(), *field,
                                                             request.contacts, result)
                                   : link_meets_octree(link, poses[l], env.octree(), request, result));
    const std::string& name = m_->robot().links()[l].name;
    std::vector<std::uint32_t>& near = tl_near_objects;
    if (request.objects) {
      Vec3 lo, hi;
      ball_box(poses[l] * bound.center, bound.radius + m_->paddings()[l], lo, hi);
      objects_near(env.objects(), near_robot, lo, hi, near);
    }
    for (std::size_t k = 0; request.objects && k < near.size() && !(hit && !request.all_links); ++k) {
      if (env.object_allowed(name, near[k])) continue;
      hit = link_meets_object(link, poses[l], env.objects()[near[k]], request, result) || hit;
    }
    result.collision = result.collision || hit;
  }
  if (!request.distance) return result;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t l = 0; l < m_->shapes().size(); ++l) {
    if (m_->shapes()[l].empty() || (only != nullptr && !(*only)[l])) continue;
    const int link = static_cast<int>(l);
    if (use_octree) best = link_octree_distance(link, poses[l], env.octree(), best, request.solids, result);
    for (std::size_t o = 0; request.objects && o < env.objects().size(); ++o) {
      if (env.object_allowed(m_->robot().links()[l].name, o)) continue;
      const CollisionObject& object = env.objects()[o];
      const double gap = (poses[l] * m_->bounds()[l].center - object.pose * object.bound_center).norm() -
                         m_->bounds()[l].radius - object.bound_radius;
      if (gap < best) best = link_object_distance(link, poses[l], object, best, request.solids, result);
    }
  }
  if (!std::isfinite(best)) result.min_distance = std::numeric_limits<double>::infinity();
  return result;
}

}  // namespace bvh_collision
