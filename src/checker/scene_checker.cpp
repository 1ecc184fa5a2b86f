// SceneChecker: one state and one motion against one environment snapshot (scene_checker.h).
#include "bvh_collision/checker/scene_checker.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <stdexcept>

#include "bvh_collision/geometry/safety_margin.h"

namespace bvh_collision {

// ---- ObjectGrid ------------------------------------------------------------------------------

namespace {

// The world box of a primitive or mesh bound at `pose`: |R| half-extents around the centre.
void world_box(const Transform& pose, const Vec3& centre, const Vec3& half, Vec3& lo, Vec3& hi) {
  const Vec3 c = pose * centre;
  const Vec3 e = pose.R.cwiseAbs() * half;
  const double m = pose_margin(c.norm() + half.norm());
  lo = c - e - Vec3::Constant(m);
  hi = c + e + Vec3::Constant(m);
}

// The squared distance from p to the box [lo, hi].
double squared_box_distance(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  return (p.cwiseMax(lo).cwiseMin(hi) - p).squaredNorm();
}

}  // namespace

ObjectGrid::ObjectGrid(const std::vector<CollisionObject>& objects, const Vec3& lo, const Vec3& hi, double reach,
                       double cell)
    : origin_(lo), cell_(cell), reach_(reach) {
  for (const CollisionObject& o : objects) {
    Solid s;
    s.to_local = o.pose.inverse();
    s.primitive = o.mesh == nullptr || o.shape.kind == ObjectShape::Kind::kBox;
    s.shape = o.mesh == nullptr ? o.primitive : Primitive::box(o.shape.size);
    s.centre = o.pose * o.bound_center;
    s.radius = o.bound_radius;
    world_box(o.pose, s.primitive ? Vec3::Zero() : o.bound_center,
              s.primitive ? half_extents(s.shape) : Vec3::Constant(o.bound_radius), s.lo, s.hi);
    s.margin = pose_margin(s.centre.norm() + s.radius);
    solids_.push_back(s);
  }
  for (int i = 0; i < 3; ++i) n_[i] = std::max(1, static_cast<int>(std::ceil((hi[i] - lo[i]) / cell)));
  const std::size_t cells = static_cast<std::size_t>(n_[0]) * n_[1] * n_[2];
  start_.assign(cells + 1, 0);
  // A cell lists an object when the object's box comes within reach of the cell's box (the ball
  // of a query centred in the cell, of radius up to reach, can then meet it).
  const double half_diagonal = 0.5 * std::sqrt(3.0) * cell;
  std::vector<std::vector<std::uint32_t>> lists(cells);
  for (std::size_t o = 0; o < solids_.size(); ++o) {
    const Solid& s = solids_[o];
    int first[3], last[3];
    for (int i = 0; i < 3; ++i) {
      first[i] = std::clamp(static_cast<int>(std::floor((s.lo[i] - reach - lo[i]) / cell)), 0, n_[i] - 1);
      last[i] = std::clamp(static_cast<int>(std::floor((s.hi[i] + reach - lo[i]) / cell)), 0, n_[i] - 1);
    }
    for (int z = first[2]; z <= last[2]; ++z) {
      for (int y = first[1]; y <= last[1]; ++y) {
        for (int x = first[0]; x <= last[0]; ++x) {
          const Vec3 centre = lo + cell * Vec3(x + 0.5, y + 0.5, z + 0.5);
          const double within = reach + half_diagonal;
          if (squared_box_distance(centre, s.lo, s.hi) > within * within * (1 + 1e-9)) continue;
          lists[(static_cast<std::size_t>(z) * n_[1] + y) * n_[0] + x].push_back(static_cast<std::uint32_t>(o));
        }
      }
    }
  }
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] = start_[c] + static_cast<std::uint32_t>(lists[c].size());
  list_.reserve(start_.back());
  for (const auto& l : lists) list_.insert(list_.end(), l.begin(), l.end());
}

int ObjectGrid::cell_of(const Vec3& p) const {
  int at[3];
  for (int i = 0; i < 3; ++i) {
    const double f = (p[i] - origin_[i]) / cell_;
    if (!(f >= 0.0) || f >= n_[i]) return -1;  // outside (or not a number): every object
    at[i] = static_cast<int>(f);
  }
  return (at[2] * n_[1] + at[1]) * n_[0] + at[0];
}

bool ObjectGrid::ball_meets(int o, const Vec3& centre, double radius) const {
  const Solid& s = solids_[o];
  const double reach = radius + s.margin + pose_margin(centre.norm());
  if (squared_box_distance(centre, s.lo, s.hi) > reach * reach) return false;
  if (!s.primitive) return (centre - s.centre).squaredNorm() <= (reach + s.radius) * (reach + s.radius);
  const Vec3 p = s.to_local * centre;
  return (closest_point(s.shape, p) - p).squaredNorm() <= reach * reach;
}

// ---- SceneChecker: set-up ----------------------------------------------------------------------

namespace {

// Growth below which an interval that still fails at tolerance 0 goes to exact advancement.
constexpr double kExactGrowth = 2e-3;

struct Scratch {
  std::vector<double> growth, state, speed;
};

Scratch& scratch() {
  thread_local Scratch s;
  return s;
}

// The levels tests go through, coarsest first, down to the finest that serves `tolerance`: at
// a tolerance the coarsest level up to half of it (or up to it), exact: every level.
std::vector<const ProxyLevel*> levels_for(const RobotCollisionModel& m, double tolerance) {
  const ProxyLevel* finest = nullptr;
  if (tolerance > 0.0) finest = m.proxies_for(tolerance / 2);
  if (finest == nullptr && tolerance > 0.0) finest = m.proxies_for(tolerance);
  std::vector<const ProxyLevel*> out;
  for (const ProxyLevel& p : m.proxy_levels()) {
    if (finest == nullptr || p.level >= finest->level) out.push_back(&p);
  }
  std::sort(out.begin(), out.end(), [](const ProxyLevel* a, const ProxyLevel* b) { return a->level > b->level; });
  return out;
}

}  // namespace

SceneChecker::SceneChecker(CollisionChecker checker, std::shared_ptr<const Environment> environment,
                           const SceneCheckOptions& options)
    : checker_(std::move(checker)), env_(std::move(environment)), options_(options) {
  if (!env_) throw std::invalid_argument("scene checker: no environment");
  if (!is_rigid(options.root_pose)) throw std::invalid_argument("scene checker: the root pose is not a finite rigid transform");
  if (!std::isfinite(options.tolerance) || options.tolerance < 0.0) throw std::invalid_argument("scene checker: tolerance must be finite and >= 0");
  const RobotCollisionModel& m = checker_.collision_model();
  proxies_ = levels_for(m, options.tolerance);
  level_ = proxies_.empty() ? 0.0 : proxies_.back()->level;
  proxies_decide_self_ = !proxies_.empty() && options.tolerance >= level_;
  proxies_decide_objects_ = !proxies_.empty() && options.tolerance >= level_ / 2;
  double reach = 0.0;
  for (std::size_t l = 0; l < m.shapes().size(); ++l) {
    if (m.shapes()[l].empty()) continue;
    links_.push_back(static_cast<int>(l));
    reach = std::max(reach, m.bounds()[l].radius + m.paddings()[l]);
  }
  if (options.environment && !env_->objects().empty()) {
    // Cells of 10 cm over the reach around the root; queries up to the largest link ball plus
    // 5 cm of growth use the cell's list.
    const Vec3 around = Vec3::Constant(checker_.reach() + 0.1);
    grid_ = ObjectGrid(env_->objects(), options.root_pose.t - around, options.root_pose.t + around, reach + 0.05, 0.1);
  }
  if (options.environment && !env_->octree().empty()) {
    field_ = checker_.kept_distance_field(*env_, options.root_pose);
    if (!field_) field_ = checker_.prepare_distance_field(*env_, options.root_pose);
  }
}

void SceneChecker::pose_links(const double* state, Posed& posed) const {
  const RobotCollisionModel& m = checker_.collision_model();
  posed.state = state;
  m.kinematics().compute(state, posed.poses);
  posed.centres.resize(posed.poses.size());
  for (const int l : links_) {
    posed.poses[l] = options_.root_pose * posed.poses[l];
    posed.centres[l] = posed.poses[l] * m.bounds()[l].center;
  }
}

double SceneChecker::link_growth(int link, const double* start, const double* goal, double half) const {
  const double g = checker_.link_speed(link, start, goal) * half;
  return g * (1.0 + 1e-9) + pose_margin(g);
}

// ---- SceneChecker: one posed state ----------------------------------------------------------------

SceneChecker::Answer SceneChecker::self_check(const Posed& s) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const auto& bounds = m.bounds();
  for (std::size_t p = 0; p < m.checked_pairs().size(); ++p) {
    const auto [a, b] = m.checked_pairs()[p];
    const double pads = m.paddings()[a] + m.paddings()[b] + s.grow(a) + s.grow(b);
    const Vec3& ca = s.centres[a];
    const Vec3& cb = s.centres[b];
    const double reach = bounds[a].radius + bounds[b].radius + pads +
                         pose_margin(ca.norm() + cb.norm() + bounds[a].radius + bounds[b].radius);
    if ((ca - cb).squaredNorm() > reach * reach) continue;
    if (m.pair_clearance().lower_bound(p, s.state) > pads) continue;
    const bool apart = std::any_of(proxies_.begin(), proxies_.end(), [&](const ProxyLevel* level) {
      return !proxies_overlap(level->links[a], s.poses[a], level->links[b], s.poses[b], pads);
    });
    if (apart) continue;
    if (s.growth != nullptr) return Answer::kNear;
    if (proxies_decide_self_) return Answer::kHit;
    SelfCollisionResult r;
    if (checker_.pair_collides(a, b, s.poses, SelfCollisionRequest{options_.tolerance}, r)) return Answer::kHit;
  }
  return Answer::kFree;
}

bool SceneChecker::link_meets_object_exact(int link, const Transform& pose, int object) const {
  const RobotCollisionModel& m = checker_.collision_model();
  const CollisionObject& o = env_->objects()[object];
  const detail::ShapeRef obstacle{o.mesh.get(), o.hull.get(), o.primitive};
  detail::PairRequest r;
  r.padding = m.paddings()[link];
  r.tolerance = options_.tolerance;
  QueryStats stats;
  for (const LinkShape& shape : m.shapes()[link]) {
    if (detail::shapes_collide(m.ref(shape), pose * shape.origin, obstacle, o.pose, r, nullptr, stats)) return true;
  }
  return false;
}

SceneChecker::Answer SceneChecker::objects_check(const Posed& s) const {
  if (grid_.size() == 0) return Answer::kFree;
  const RobotCollisionModel& m = checker_.collision_model();
  for (const int l : links_) {
    const double pad = m.paddings()[l] + s.grow(l);
    const Vec3& c = s.centres[l];
    const double r = m.bounds()[l].radius + pad;
    Answer answer = Answer::kFree;
    grid_.for_each_near(c, r, [&](int o) {
      if (answer != Answer::kFree || !grid_.ball_meets(o, c, r)) return;
      const bool apart = std::any_of(proxies_.begin(), proxies_.end(), [&](const ProxyLevel* level) {
        return !proxy_meets_obstacle(level->links[l], s.poses[l], pad,
                                     [&](const Vec3& pc, double pr, bool) { return grid_.ball_meets(o, pc, pr); });
      });
      if (apart) return;
      if (s.growth != nullptr) {
        answer = Answer::kNear;
      } else if ((proxies_decide_objects_ && grid_.exact_ball_test(o)) || link_meets_object_exact(l, s.poses[l], o)) {
        answer = Answer::kHit;
      }
    });
    if (answer != Answer::kFree) return answer;
  }
  return Answer::kFree;
}

SceneChecker::Answer SceneChecker::octree_check(const Posed& s) const {
  const Octree& tree = env_->octree();
  if (tree.empty()) return Answer::kFree;
  const RobotCollisionModel& m = checker_.collision_model();
  for (const int l : links_) {
    const double pad = m.paddings()[l] + s.grow(l);
    const Vec3& c = s.centres[l];
    if (field_ && field_->lower_bound(c) > grown_radius(m.bounds()[l].radius + pad) + pose_margin(c.norm() + m.bounds()[l].radius)) continue;
    const bool apart = std::any_of(proxies_.begin(), proxies_.end(), [&](const ProxyLevel* level) {
      return !proxy_meets_obstacle(level->links[l], s.poses[l], pad, [&](const Vec3& pc, double pr, bool leaf) {
        if (field_ && field_->lower_bound(pc) > grown_radius(pr)) return false;
        if (!leaf) return true;
        if (field_) {
          if (const std::optional<bool> known = field_->ball_meets_occupied(pc, pr)) return *known;
        }
        return !tree.occupied_in_sphere(pc, pr, true).empty();
      });
    });
    if (apart) continue;
    if (s.growth != nullptr) return Answer::kNear;
    if (proxies_decide_objects_) return Answer::kHit;
    EnvironmentRequest request;
    request.tolerance = options_.tolerance;
    request.contacts = false;
    EnvironmentResult result;
    if (checker_.link_meets_octree(l, s.poses[l], tree, request, result)) return Answer::kHit;
  }
  return Answer::kFree;
}

SceneChecker::Answer SceneChecker::check_posed(const Posed& s) const {
  if (options_.self) {
    if (const Answer a = self_check(s); a != Answer::kFree) return a;
  }
  if (!options_.environment) return Answer::kFree;
  if (const Answer a = objects_check(s); a != Answer::kFree) return a;
  return octree_check(s);
}

bool SceneChecker::collides(const double* state) const {
  thread_local Posed posed;
  pose_links(state, posed);
  posed.growth = nullptr;
  return check_posed(posed) != Answer::kFree;
}

// ---- SceneChecker: motions ----------------------------------------------------------------------

namespace {

struct Interval {
  double lo, hi;
};

// The end of the certified intervals' run from 0 (they may overlap only at their ends).
double certified_prefix(std::vector<Interval> done) {
  std::sort(done.begin(), done.end(), [](const Interval& a, const Interval& b) { return a.lo < b.lo; });
  double end = 0.0;
  for (const Interval& i : done) {
    if (i.lo > end) break;
    end = std::max(end, i.hi);
  }
  return end;
}

}  // namespace

MotionResult SceneChecker::check_motion(const double* start, const double* goal) const {
  const std::size_t n = checker_.model().variable_count();
  for (std::size_t j = 0; j < n; ++j) {
    if (!std::isfinite(start[j]) || !std::isfinite(goal[j])) {
      throw std::invalid_argument("motion check: " + checker_.model().variable_names()[j] + " is not finite");
    }
  }
  MotionResult result;
  Scratch& s = scratch();
  thread_local Posed posed;
  s.state.resize(n);
  auto at = [&](double f) {
    for (std::size_t j = 0; j < n; ++j) s.state[j] = f >= 1.0 ? goal[j] : start[j] + f * (goal[j] - start[j]);
    return s.state.data();
  };
  auto collide_at = [&](double f) {
    result.colliding_fraction = f;
    result.certified = true;
    return result;
  };
  // The ends first: a planner's goal state is often the colliding one.
  for (const double f : {1.0, 0.0}) {
    ++result.states_checked;
    if (collides(at(f))) return collide_at(f);
  }
  const RobotCollisionModel& m = checker_.collision_model();
  s.speed.assign(m.shapes().size(), 0.0);
  for (const int l : links_) s.speed[l] = checker_.link_speed(l, start, goal);
  s.growth.assign(m.shapes().size(), 0.0);
  std::vector<Interval> done;
  std::deque<Interval> todo{{0.0, 1.0}};
  while (!todo.empty()) {
    const Interval i = todo.front();
    todo.pop_front();
    if (++result.states_checked > options_.max_intervals) {
      result.message = "not certified after " + std::to_string(options_.max_intervals) + " intervals";
      result.last_valid_fraction = certified_prefix(done);
      return result;
    }
    const double mid = 0.5 * (i.lo + i.hi), half = 0.5 * (i.hi - i.lo);
    double largest = 0.0;
    for (const int l : links_) {
      const double g = s.speed[l] * half;
      s.growth[l] = g * (1.0 + 1e-9) + pose_margin(g);
      largest = std::max(largest, s.growth[l]);
    }
    pose_links(at(mid), posed);
    posed.growth = s.growth.data();
    if (check_posed(posed) == Answer::kFree) {
      done.push_back(i);
      continue;
    }
    posed.growth = nullptr;
    if (check_posed(posed) != Answer::kFree) {
      result.last_valid_fraction = certified_prefix(done);
      return collide_at(mid);
    }
    // Proxies within the level of the links, grown by at most `largest`: a failed interval
    // puts a link within level + 2 largest (a self pair) of a collision at its midpoint.
    if (!proxies_.empty() && options_.tolerance > 0.0 && level_ + 2.0 * largest <= options_.tolerance) {
      result.last_valid_fraction = certified_prefix(done);
      return collide_at(mid);
    }
    if (largest <= kExactGrowth) {
      // Ambiguous at this size: exact conservative advancement over the interval.
      std::vector<double> a(start, start + n), b(n);
      std::copy(at(i.lo), at(i.lo) + n, a.begin());
      std::copy(at(i.hi), at(i.hi) + n, b.begin());
      MotionRequest request;
      request.self = options_.self;
      request.environment = options_.environment;
      request.tolerance = options_.tolerance;
      request.root_pose = options_.root_pose;
      request.min_clearance = options_.min_clearance;
      const MotionResult sub = checker_.check_motion(a.data(), b.data(), *env_, request);
      result.states_checked += sub.states_checked;
      if (!sub.valid) {
        done.push_back({i.lo, i.lo + sub.last_valid_fraction * (i.hi - i.lo)});
        result.last_valid_fraction = certified_prefix(done);
        result.message = sub.message;
        if (sub.colliding_fraction >= 0.0) return collide_at(i.lo + sub.colliding_fraction * (i.hi - i.lo));
        return result;
      }
      done.push_back(i);
      continue;
    }
    todo.push_back({i.lo, mid});
    todo.push_back({mid, i.hi});
  }
  result.valid = result.certified = true;
  result.last_valid_fraction = 1.0;
  return result;
}

}  // namespace bvh_collision
