// The batch kernel of the link proxies (model/proxy_batch.h), written once over GCC vector
// types of W doubles and compiled twice: proxy_batch_generic.cpp (the default -O2 build, W = 2,
// the SSE2 registers x86-64 always has) and proxy_batch_avx2.cpp (-mavx2, W = 4). The unit that
// includes it defines PROXY_BATCH_ISA (generic or avx2), which names its entry points, and
// PROXY_BATCH_WIDTH (W).
//
// W states run in the lanes: forward kinematics, the bounding-sphere broad phase and a proxy
// tree traversal shared by the lanes, each pair of spheres tested in every lane at once and kept
// while some lane still overlaps (a lane mask travels with each entry of the stack). A lane found
// colliding leaves every later test.
//
// Floating point: no fused multiply-add (the units are built with -ffp-contract=off and without
// -mfma), so the two builds round alike and answer alike. The sphere tests are those of
// proxies_overlap (narrowphase/link_proxy_pairs.cpp) with its margin, kPoseMargin of the poses' magnitude,
// which covers the rounding of poses carried down a chain of ~100 joints at a few units in the
// last place each; the sine and cosine below are within 1e-15 of exact (bound below), so the
// poses they give round like those of the C library's and the same margin covers them.
//
// Everything here has internal linkage, and only plain types and builtins are used (see
// proxy_batch_plan.h on why); the traversal core's templates (geometry/tree_walk.h) are
// instantiated here only with this unit's own types and lambdas, so their code has internal
// linkage too and is never shared with the other build of the kernel.
#include <cstring>

#include "bvh_collision/model/detail/proxy_batch_plan.h"
#include "bvh_collision/geometry/sin_cos.h"
#include "bvh_collision/geometry/tree_walk.h"

#if !defined(PROXY_BATCH_ISA) || !defined(PROXY_BATCH_WIDTH)
#error "define PROXY_BATCH_ISA and PROXY_BATCH_WIDTH before including proxy_batch_kernel.h"
#endif
#define PROXY_BATCH_CAT2(a, b) a##_##b
#define PROXY_BATCH_CAT(a, b) PROXY_BATCH_CAT2(a, b)
#define PROXY_BATCH_NAME(name) PROXY_BATCH_CAT(name, PROXY_BATCH_ISA)

// Four doubles are passed between this unit's own inline functions only (internal linkage), so
// GCC's note that their calling convention differs with and without AVX does not apply.
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

namespace bvh_collision::proxy_batch {
namespace {

// W states per vector: the kernel's kLanes states run as kLanes / W groups of W.
constexpr int W = PROXY_BATCH_WIDTH;
static_assert(kLanes % W == 0, "the lane groups must fill kLanes");
typedef double V __attribute__((vector_size(8 * W)));
typedef long long M __attribute__((vector_size(8 * W)));

inline V splat(double x) { return V{} + x; }
inline unsigned lane_bits(M m) {
  unsigned bits = 0;
  for (int l = 0; l < W; ++l) bits |= static_cast<unsigned>(m[l] & 1) << l;
  return bits;
}
inline V load(const double* p) {
  V v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
// m ? a : b lane by lane, in bit operations (GCC and clang both take them).
inline V select(M m, V a, V b) {
  M ai, bi;
  std::memcpy(&ai, &a, sizeof a);
  std::memcpy(&bi, &b, sizeof b);
  const M r = (m & ai) | (~m & bi);
  V out;
  std::memcpy(&out, &r, sizeof out);
  return out;
}
constexpr unsigned kAllLanes = (1u << W) - 1;

// sin and cos of W values: geometry/sin_cos.h's operations and constants (its bound: within
// ~5e-16 of exact for |x| <= 1.6e6), lane by lane; lanes beyond that (or not finite) take the C
// library's.
inline void sincos_lanes(V x, V& s, V& c) {
  using namespace sin_cos_constants;
  const V shifted = x * splat(kTwoOverPi) + splat(kRoundShift);
  M quadrant;
  std::memcpy(&quadrant, &shifted, sizeof quadrant);
  const V k = shifted - splat(kRoundShift);
  const V r = ((x - k * splat(kPiOver2Hi)) - k * splat(kPiOver2Mid)) - k * splat(kPiOver2Lo);
  const V r2 = r * r;
  V ps = splat(kSine[0]);
  for (int i = 1; i < 8; ++i) ps = ps * r2 + splat(kSine[i]);
  const V sin_r = r + r * r2 * ps;
  V pc = splat(kCosine[0]);
  for (int i = 1; i < 9; ++i) pc = pc * r2 + splat(kCosine[i]);
  const V cos_r = splat(1.0) - r2 * pc;
  // Quadrant k mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
  const M zero = {};
  const M swap = (quadrant & 1) != zero;
  const M negate_sin = (quadrant & 2) != zero;
  const M negate_cos = ((quadrant + 1) & 2) != zero;
  const V s0 = select(swap, cos_r, sin_r);
  const V c0 = select(swap, sin_r, cos_r);
  s = select(negate_sin, -s0, s0);
  c = select(negate_cos, -c0, c0);
  const V magnitude = select(x < splat(0.0), -x, x);
  const unsigned outside = lane_bits(~(magnitude <= splat(kReducedRange)));
  if (outside != 0) {
    for (int l = 0; l < W; ++l) {
      if (outside & (1u << l)) s[l] = __builtin_sin(x[l]), c[l] = __builtin_cos(x[l]);
    }
  }
}

// A link pose in the lanes: rotation row-major in [0, 9), translation in [9, 12).
struct Pose {
  V m[12];
};

// parent * fixed (fixed the same in every lane).
inline void compose_fixed(const Pose& p, const double* f, Pose& out) {
  for (int r = 0; r < 3; ++r) {
    const V a = p.m[r * 3], b = p.m[r * 3 + 1], c = p.m[r * 3 + 2];
    for (int col = 0; col < 3; ++col) out.m[r * 3 + col] = a * f[col] + b * f[3 + col] + c * f[6 + col];
    out.m[9 + r] = a * f[9] + b * f[10] + c * f[11] + p.m[9 + r];
  }
}

inline V joint_value(const Step& step, const double* const* lanes) {
  V q;
  for (int l = 0; l < W; ++l) q[l] = lanes[l][step.variable];
  return q * splat(step.multiplier) + splat(step.offset);
}

// out = out * rotation(q) about the step's axis.
inline void apply_rotation(const Step& step, V q, Pose& out) {
  V s, c;
  sincos_lanes(q, s, c);
  if (step.kind == kAxisRotation) {
    // About +-e_k: e_i -> c e_i + s e_j, e_j -> -s e_i + c e_j (columns i and j mix).
    s = s * splat(step.sign);
    const int i = (step.axis_index + 1) % 3, j = (step.axis_index + 2) % 3;
    for (int r = 0; r < 3; ++r) {
      const V a = out.m[r * 3 + i], b = out.m[r * 3 + j];
      out.m[r * 3 + i] = c * a + s * b;
      out.m[r * 3 + j] = c * b - s * a;
    }
    return;
  }
  // Rodrigues: R = c I + s [a]x + (1 - c) a a^T.
  const double x = step.axis[0], y = step.axis[1], z = step.axis[2];
  const V t = splat(1.0) - c;
  const V rot[9] = {c + t * (x * x),     t * (x * y) - s * z, t * (x * z) + s * y,
                    t * (x * y) + s * z, c + t * (y * y),     t * (y * z) - s * x,
                    t * (x * z) - s * y, t * (y * z) + s * x, c + t * (z * z)};
  for (int r = 0; r < 3; ++r) {
    const V a = out.m[r * 3], b = out.m[r * 3 + 1], d = out.m[r * 3 + 2];
    for (int col = 0; col < 3; ++col) out.m[r * 3 + col] = a * rot[col] + b * rot[3 + col] + d * rot[6 + col];
  }
}

void forward_kinematics(const Plan& plan, const double* const* lanes, Pose* poses) {
  Pose& root = poses[plan.root];
  for (int e = 0; e < 12; ++e) root.m[e] = splat(e < 9 && e % 4 == 0 ? 1.0 : 0.0);
  for (int k = 0; k < plan.step_count; ++k) {
    const Step& step = plan.steps[k];
    Pose& out = poses[step.link];
    compose_fixed(poses[step.parent], step.fixed, out);
    if (step.kind == kFixedStep || step.variable < 0) continue;
    const V q = joint_value(step, lanes);
    if (step.kind == kSlide) {
      for (int r = 0; r < 3; ++r) {
        out.m[9 + r] += (out.m[r * 3] * splat(step.axis[0]) + out.m[r * 3 + 1] * splat(step.axis[1]) +
                         out.m[r * 3 + 2] * splat(step.axis[2])) * q;
      }
    } else {
      apply_rotation(step, q, out);
    }
  }
}

// A proxy sphere tree as the traversal core walks it (geometry/tree_walk.h): stored depth first,
// each sphere knowing the index past its subtree. a's side carries, with each sphere, the lanes
// still to test below it.
struct LaneSphere {
  std::int32_t index;
  unsigned lanes;
};
struct SphereTree {
  using Node = std::int32_t;
  const Sphere* s;
  bool is_leaf(std::int32_t i) const { return s[i].skip == i + 1; }
  bool is_leaf(const LaneSphere& x) const { return is_leaf(x.index); }
  template <class F>
  void children(std::int32_t i, F&& f) const {
    for (std::int32_t k = i + 1; k < s[i].skip; k = s[k].skip) f(k);
  }
};
struct LaneSphereTree : SphereTree {
  using Node = LaneSphere;
};
// The walk's stack on the scratch memory (three words an entry; Plan::stack_capacity entries).
struct ScratchStack {
  std::int32_t* words;
  int top = 0;
  bool empty() const { return top == 0; }
  void push(const NodePair<LaneSphere, std::int32_t>& p) {
    words[3 * top] = p.a.index, words[3 * top + 1] = p.b, words[3 * top + 2] = static_cast<std::int32_t>(p.a.lanes);
    ++top;
  }
  NodePair<LaneSphere, std::int32_t> pop() {
    --top;
    return {{words[3 * top], static_cast<unsigned>(words[3 * top + 2])}, words[3 * top + 1]};
  }
};

// b's proxy spheres tested against a's in the lanes of `live`: the lanes where some pair of leaf
// spheres comes within padding (plus the pose margin), as proxies_overlap decides one state.
unsigned traverse_pair(const Plan& plan, const Pair& pair, const Pose& pa, const Pose& pb, unsigned live,
                       std::int32_t* stack) {
  const Link& la = plan.links[pair.a];
  const Link& lb = plan.links[pair.b];
  const Sphere* sa = plan.spheres + la.first;
  const Sphere* sb = plan.spheres + lb.first;
  // b in a's frame: R = Ra^T Rb, t = Ra^T (tb - ta).
  V r[9], t[3];
  const V dt[3] = {pb.m[9] - pa.m[9], pb.m[10] - pa.m[10], pb.m[11] - pa.m[11]};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r[i * 3 + j] = pa.m[i] * pb.m[j] + pa.m[3 + i] * pb.m[3 + j] + pa.m[6 + i] * pb.m[6 + j];
    t[i] = pa.m[i] * dt[0] + pa.m[3 + i] * dt[1] + pa.m[6 + i] * dt[2];
  }
  V norm_a, norm_b;
  const V na2 = pa.m[9] * pa.m[9] + pa.m[10] * pa.m[10] + pa.m[11] * pa.m[11];
  const V nb2 = pb.m[9] * pb.m[9] + pb.m[10] * pb.m[10] + pb.m[11] * pb.m[11];
  for (int l = 0; l < W; ++l) norm_a[l] = __builtin_sqrt(na2[l]), norm_b[l] = __builtin_sqrt(nb2[l]);
  const V slack = splat(pair.padding) +
                  splat(plan.pose_margin) * (splat(1.0) + (norm_a + norm_b + splat(la.extent + lb.extent)));
  unsigned hits = 0;
  unsigned near = 0;  // the lanes where the pair just visited came within reach
  ScratchStack walk_stack{stack};
  const LaneSphereTree ta{{sa}};
  const SphereTree tb{sb};
  depth_first_pair_walk_on(walk_stack, ta, tb, LaneSphere{0, live}, 0, [&](const LaneSphere& x, std::int32_t j) {
    const unsigned mask = x.lanes & ~hits;
    if (mask == 0) return Visit::kSkip;
    const Sphere& a = sa[x.index];
    const Sphere& b = sb[j];
    const V dx = splat(a.c[0]) - (r[0] * b.c[0] + r[1] * b.c[1] + r[2] * b.c[2] + t[0]);
    const V dy = splat(a.c[1]) - (r[3] * b.c[0] + r[4] * b.c[1] + r[5] * b.c[2] + t[1]);
    const V dz = splat(a.c[2]) - (r[6] * b.c[0] + r[7] * b.c[1] + r[8] * b.c[2] + t[2]);
    const V reach = splat(a.r + b.r) + slack;
    // Not "apart" (a NaN stays in, as in proxies_overlap).
    near = mask & ~lane_bits(dx * dx + dy * dy + dz * dz > reach * reach);
    return near == 0 ? Visit::kSkip : Visit::kEnter;
  }, [&](const LaneSphere&, std::int32_t) {
    hits |= near;
    return hits == live;
  }, [&](const LaneSphere& x, std::int32_t j, auto&& push) {
    // The larger sphere is opened (a leaf never); its children carry the lanes still in.
    const Sphere& a = sa[x.index];
    const Sphere& b = sb[j];
    if (!ta.is_leaf(x) && (tb.is_leaf(j) || a.r >= b.r)) {
      ta.children(x.index, [&](std::int32_t k) { push(LaneSphere{k, near}, j); });
    } else {
      tb.children(j, [&](std::int32_t k) { push(LaneSphere{x.index, near}, k); });
    }
  });
  return hits;
}

// The lanes where pair's bounding spheres come within reach, and the smallest (distance /
// reach)^2 among them: check_self's broad phase.
unsigned broad_phase(const Pair& pair, const double* centers, unsigned live, double& key) {
  const double* ca = centers + 3 * W * pair.a;
  const double* cb = centers + 3 * W * pair.b;
  const V dx = load(ca) - load(cb), dy = load(ca + W) - load(cb + W), dz = load(ca + 2 * W) - load(cb + 2 * W);
  const double reach = pair.reach;  // not grown by the tolerance: narrowphase/tolerance_policy.h
  const V d2 = dx * dx + dy * dy + dz * dz;
  const unsigned near = live & lane_bits(d2 <= splat(reach * reach));
  if (near == 0) return 0;
  double closest = reach * reach;
  for (int l = 0; l < W; ++l) {
    if ((near & (1u << l)) && d2[l] < closest) closest = d2[l];
  }
  key = closest / (reach * reach);
  return near;
}

// Lanes whose clearance grid of the pair clears its padding leave it (model/pair_clearance.h).
unsigned graded_lanes(const Plan& plan, const Pair& pair, const double* const* lanes, unsigned near) {
  for (int l = 0; l < W; ++l) {
    if ((near & (1u << l)) && plan.clearance(plan.clearance_context, pair.index, lanes[l]) > pair.padding) {
      near &= ~(1u << l);
    }
  }
  return near;
}

// The pairs in reach of some lane, deepest overlap first (those collide most often, and a lane
// leaves at its first collision), as check_self orders them for one state.
int pairs_in_reach(const Plan& plan, const double* centers, Candidate* out) {
  int count = 0;
  for (int k = 0; k < plan.pair_count; ++k) {
    const Pair& pair = plan.pairs[k];
    if (plan.links[pair.a].count == 0 || plan.links[pair.b].count == 0) continue;
    double key;
    const unsigned near = broad_phase(pair, centers, kAllLanes, key);
    if (near == 0) continue;
    int at = count++;
    for (; at > 0 && out[at - 1].key > key; --at) out[at] = out[at - 1];  // insertion: tens of pairs
    out[at] = {key, k, near};
  }
  return count;
}

void link_centers(const Plan& plan, const Pose* poses, double* centers) {
  for (int l = 0; l < plan.link_count; ++l) {
    const Link& link = plan.links[l];
    if (link.bound_r < 0) continue;
    const Pose& p = poses[l];
    for (int i = 0; i < 3; ++i) {
      const V c = p.m[i * 3] * link.bound_c[0] + p.m[i * 3 + 1] * link.bound_c[1] + p.m[i * 3 + 2] * link.bound_c[2] +
                  p.m[9 + i];
      std::memcpy(centers + 3 * W * l + W * i, &c, sizeof c);
    }
  }
}

// One group of W states: the lanes among them that collide.
unsigned check_group(const Plan& plan, const double* const* lanes, const Scratch& scratch) {
  Pose* poses = reinterpret_cast<Pose*>(scratch.poses);
  forward_kinematics(plan, lanes, poses);
  link_centers(plan, poses, scratch.centers);
  const int count = pairs_in_reach(plan, scratch.centers, scratch.candidates);
  unsigned hits = 0;
  for (int k = 0; k < count && hits != kAllLanes; ++k) {
    const Pair& pair = plan.pairs[scratch.candidates[k].pair];
    unsigned near = scratch.candidates[k].lanes & ~hits;
    if (near != 0 && pair.graded) near = graded_lanes(plan, pair, lanes, near);
    if (near != 0) hits |= traverse_pair(plan, pair, poses[pair.a], poses[pair.b], near, scratch.stack);
  }
  return hits;
}

}  // namespace

// Each entry takes kLanes states and runs them as groups of W; a lane's answer does not depend
// on the group it ran in (every pair in reach of it is tested until one overlaps), so the builds
// answer alike whatever their width.
void PROXY_BATCH_NAME(forward_kinematics)(const Plan& plan, const double* const* lanes, const Scratch& scratch,
                                          double* out) {
  auto copy = [&](int link, int group) {
    for (int i = link * 12; i < link * 12 + 12; ++i) {
      for (int l = 0; l < W; ++l) out[i * kLanes + group + l] = scratch.poses[i * W + l];
    }
  };
  for (int group = 0; group < kLanes; group += W) {
    forward_kinematics(plan, lanes + group, reinterpret_cast<Pose*>(scratch.poses));
    copy(plan.root, group);  // the computed links only: the others hold whatever was there
    for (int k = 0; k < plan.step_count; ++k) copy(plan.steps[k].link, group);
  }
}

void PROXY_BATCH_NAME(check_block)(const Plan& plan, const double* const* lanes, unsigned char* out,
                                   const Scratch& scratch) {
  for (int group = 0; group < kLanes; group += W) {
    const unsigned hits = check_group(plan, lanes + group, scratch);
    for (int l = 0; l < W; ++l) out[group + l] = (hits >> l) & 1;
  }
}

void PROXY_BATCH_NAME(sincos)(const double* x, double* s, double* c) {
  for (int group = 0; group < kLanes; group += W) {
    V vs, vc;
    sincos_lanes(load(x + group), vs, vc);
    std::memcpy(s + group, &vs, sizeof vs);
    std::memcpy(c + group, &vc, sizeof vc);
  }
}

}  // namespace bvh_collision::proxy_batch

#undef PROXY_BATCH_NAME
#undef PROXY_BATCH_CAT
#undef PROXY_BATCH_CAT2
