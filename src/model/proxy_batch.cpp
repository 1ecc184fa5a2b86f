// ProxyBatch: the flat plan of a proxy level, the run-time choice of kernel, and each thread's
// working memory (model/proxy_batch.h). The kernels are in proxy_batch_generic.cpp and
// proxy_batch_avx2.cpp.
#include "bvh_collision/model/proxy_batch.h"

#include <algorithm>
#include <cstdint>
#include <stdexcept>

#include "bvh_collision/model/pair_clearance.h"
#include "bvh_collision/model/robot_accelerators.h"
#include "bvh_collision/model/robot_collision_model.h"
#include "bvh_collision/geometry/safety_margin.h"
#include "bvh_collision/geometry/tree_walk.h"

namespace bvh_collision {

namespace pb = proxy_batch;

namespace {

pb::Step flat_step(const KinematicsPlan::Step& step) {
  pb::Step out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.fixed[r * 3 + c] = step.fixed.R(r, c);
    out.fixed[9 + r] = step.fixed.t[r];
    out.axis[r] = step.axis_vector[r];
  }
  out.link = step.link;
  out.parent = step.parent;
  out.variable = step.variable;
  out.multiplier = step.multiplier;
  out.offset = step.offset;
  switch (step.type) {
    case JointType::kRevolute:
    case JointType::kContinuous:
      out.kind = step.axis >= 0 ? pb::kAxisRotation : pb::kGeneralRotation;
      out.axis_index = step.axis;
      out.sign = step.axis >= 0 ? step.axis_vector[step.axis] : 1.0;
      break;
    case JointType::kPrismatic:
      out.kind = pb::kSlide;
      break;
    default:  // fixed; floating and planar at identity, as a self check computes them
      out.kind = pb::kFixedStep;
      out.variable = -1;
  }
  return out;
}

// Depth (spheres on the longest root-to-leaf path) and most children of one sphere tree.
void tree_shape(const std::vector<ProxySphere>& s, int& depth, int& children) {
  // Walked whole, in order: the open subtrees above each node are its ancestors.
  std::vector<std::int32_t> open;  // the skip of each open ancestor, innermost last
  std::vector<int> count;          // children seen of each
  skip_walk(static_cast<std::int32_t>(s.size()), [&](std::int32_t i) { return s[i].skip; }, [&](std::int32_t i, bool) {
    while (!open.empty() && open.back() <= i) open.pop_back(), count.pop_back();
    if (!count.empty()) children = std::max(children, ++count.back());
    open.push_back(s[i].skip), count.push_back(0);
    depth = std::max(depth, static_cast<int>(open.size()));
    return Visit::kEnter;
  });
}

// One thread's kernel memory, grown to the largest plan it has run.
struct BatchScratch {
  std::vector<double> memory;
  std::vector<std::int32_t> stack;
  std::vector<pb::Candidate> candidates;
  pb::Scratch get(const pb::Plan& plan) {
    const std::size_t pose_doubles = static_cast<std::size_t>(plan.link_count) * 12 * pb::kLanes;
    const std::size_t center_doubles = static_cast<std::size_t>(plan.link_count) * 3 * pb::kLanes;
    if (memory.size() < pose_doubles + center_doubles + 8) memory.resize(pose_doubles + center_doubles + 8);
    if (stack.size() < 3 * static_cast<std::size_t>(plan.stack_capacity)) stack.resize(3 * plan.stack_capacity);
    if (candidates.size() < static_cast<std::size_t>(plan.pair_count)) candidates.resize(plan.pair_count);
    double* aligned = memory.data();
    while (reinterpret_cast<std::uintptr_t>(aligned) % 32 != 0) ++aligned;
    return {aligned, aligned + pose_doubles, stack.data(), candidates.data()};
  }
};

BatchScratch& batch_scratch() {
  static thread_local BatchScratch scratch;
  return scratch;
}

double clearance_bound(const void* context, std::int32_t index, const double* state) {
  return static_cast<const PairClearance*>(context)->lower_bound(static_cast<std::size_t>(index), state);
}

bool use_avx2(SimdPath path) { return resolve_simd_path(path, "the AVX2 kernel") == SimdPath::kAvx2; }

}  // namespace

ProxyBatch::ProxyBatch(const RobotCollisionModel& model, const PairClearance& clearance, const ProxyLevel& level) {
  const KinematicsPlan& kinematics = model.kinematics();
  root_ = kinematics.root();
  stride_ = static_cast<int>(model.robot().variable_count());
  for (const KinematicsPlan::Step& step : kinematics.step_list()) steps_.push_back(flat_step(step));
  int depth = 1, children = 1;
  links_.resize(model.bounds().size());
  for (std::size_t l = 0; l < links_.size(); ++l) {
    pb::Link& link = links_[l];
    const LinkBound& bound = model.bounds()[l];
    for (int i = 0; i < 3; ++i) link.bound_c[i] = bound.center[i];
    link.bound_r = bound.radius;
    link.extent = 0.0;
    link.first = static_cast<std::int32_t>(spheres_.size());
    if (l >= level.links.size() || level.links[l].empty()) continue;
    const std::vector<ProxySphere>& s = level.links[l].spheres();
    link.count = static_cast<std::int32_t>(s.size());
    link.extent = s[0].center.norm() + s[0].radius;
    for (const ProxySphere& sphere : s) {
      spheres_.push_back({{sphere.center[0], sphere.center[1], sphere.center[2]}, sphere.radius, sphere.skip});
    }
    tree_shape(s, depth, children);
  }
  // Each pop pushes at most `children` entries and the stack holds at most one open level per
  // step down either tree.
  stack_capacity_ = (2 * depth + 2) * children + 1;
  const auto& pairs = model.checked_pairs();
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    if (!level.answers(p)) continue;  // left to the exact test (model/proxy_calibration.h)
    const auto [a, b] = pairs[p];
    pb::Pair pair;
    pair.a = a, pair.b = b, pair.index = static_cast<std::int32_t>(p);
    pair.graded = clearance.has_grid(p) ? 1 : 0;
    pair.padding = model.paddings()[a] + model.paddings()[b];
    pair.reach = model.bounds()[a].radius + model.bounds()[b].radius + model.paddings()[a] + model.paddings()[b];
    pairs_.push_back(pair);
  }
}

pb::Plan ProxyBatch::plan(const PairClearance* clearance) const {
  pb::Plan p;
  p.steps = steps_.data();
  p.step_count = static_cast<std::int32_t>(steps_.size());
  p.link_count = static_cast<std::int32_t>(links_.size());
  p.root = root_;
  p.links = links_.data();
  p.spheres = spheres_.data();
  p.pairs = pairs_.data();
  p.pair_count = static_cast<std::int32_t>(pairs_.size());
  p.stride = stride_;
  p.pose_margin = kPoseMargin;
  p.clearance = clearance_bound;
  p.clearance_context = clearance;
  p.stack_capacity = stack_capacity_;
  return p;
}

void ProxyBatch::check(const PairClearance& clearance, const double* states, std::size_t count, char* out,
                       SimdPath path) const {
  const bool avx2 = use_avx2(path);
  const pb::Plan p = plan(&clearance);
  const pb::Scratch scratch = batch_scratch().get(p);
  for (std::size_t begin = 0; begin < count; begin += pb::kLanes) {
    const double* lanes[pb::kLanes];
    const std::size_t n = std::min<std::size_t>(pb::kLanes, count - begin);
    for (std::size_t l = 0; l < pb::kLanes; ++l) lanes[l] = states + (begin + std::min(l, n - 1)) * stride_;
    unsigned char hits[pb::kLanes];
    if (avx2) pb::check_block_avx2(p, lanes, hits, scratch);
    else pb::check_block_generic(p, lanes, hits, scratch);
    for (std::size_t l = 0; l < n; ++l) out[begin + l] = static_cast<char>(hits[l]);
  }
}

std::vector<double> ProxyBatch::poses(const double* states, std::size_t count, SimdPath path) const {
  if (count == 0 || count > static_cast<std::size_t>(pb::kLanes)) throw std::invalid_argument("poses: 1 to 4 states");
  const pb::Plan p = plan(nullptr);  // kinematics only: no pair is looked up
  const pb::Scratch scratch = batch_scratch().get(p);
  const double* lanes[pb::kLanes];
  for (std::size_t l = 0; l < pb::kLanes; ++l) lanes[l] = states + std::min(l, count - 1) * stride_;
  std::vector<double> out(links_.size() * 12 * pb::kLanes);
  if (use_avx2(path)) pb::forward_kinematics_avx2(p, lanes, scratch, out.data());
  else pb::forward_kinematics_generic(p, lanes, scratch, out.data());
  return out;
}

void ProxyBatch::sincos(const double* x, double* s, double* c, SimdPath path) {
  if (use_avx2(path)) pb::sincos_avx2(x, s, c);
  else pb::sincos_generic(x, s, c);
}

}  // namespace bvh_collision
