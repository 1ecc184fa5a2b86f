// The flat, plain-data form of a proxy level that the batch kernels read (model/proxy_batch.h).
// Not API (detail/). Only plain types here: the kernels are compiled once per instruction set
// (proxy_batch_kernel.h), and a kernel unit built for AVX2 must not instantiate any inline
// function another unit also instantiates (Eigen's, the standard library's), or the linker may
// keep the AVX2 copy for everyone and a CPU without AVX2 would fault in code it never asked for.
#pragma once

#include <cstdint>

namespace bvh_collision::proxy_batch {

// States per kernel call: four doubles fill one AVX2 register (two SSE2 registers).
constexpr int kLanes = 4;

enum StepKind : std::int32_t { kFixedStep = 0, kAxisRotation = 1, kGeneralRotation = 2, kSlide = 3 };

// One step of the kinematics plan (robot/robot_model.h KinematicsPlan): child = parent * fixed *
// joint(q), q = multiplier * state[variable] + offset.
struct Step {
  double fixed[12];  // rotation row-major, then translation
  double axis[3];    // unit joint axis (general rotation, slide)
  double sign = 1.0;  // rotation about +-axis_index
  double multiplier = 1.0, offset = 0.0;
  std::int32_t link = -1, parent = -1, kind = kFixedStep, axis_index = -1, variable = -1;
};

// A proxy sphere in its link's frame; `skip` is link-local (the subtree of i is [i, skip)).
struct Sphere {
  double c[3];
  double r;
  std::int32_t skip;
};

struct Link {
  double bound_c[3];         // bounding sphere in the link frame
  double bound_r;            // < 0: no geometry
  double extent;             // |c| + r of the root proxy sphere (the scale of the pose margin)
  std::int32_t first = 0;    // first proxy sphere in Plan::spheres
  std::int32_t count = 0;    // proxy spheres (0: no proxy)
};

struct Pair {
  std::int32_t a, b;      // links
  std::int32_t index;     // checked pair index (RobotCollisionModel::checked_pairs)
  std::int32_t graded;    // the pair has a clearance grid
  double padding;         // padding of a + padding of b
  double reach;           // bounding radii + paddings: the broad phase's reach (at every tolerance)
};

struct Plan {
  const Step* steps = nullptr;
  std::int32_t step_count = 0;
  std::int32_t link_count = 0, root = 0;
  const Link* links = nullptr;
  const Sphere* spheres = nullptr;
  const Pair* pairs = nullptr;
  std::int32_t pair_count = 0;
  std::int32_t stride = 0;          // doubles per state
  double pose_margin = 0.0;         // kPoseMargin (geometry/safety_margin.h)
  // A proven lower bound on pair `index`'s distance in `state` (model/pair_clearance.h).
  double (*clearance)(const void* context, std::int32_t index, const double* state) = nullptr;
  const void* clearance_context = nullptr;
  std::int32_t stack_capacity = 0;  // traversal entries a pair can need at most
};

// Working memory of one thread: link poses (12 x kLanes doubles per link, 32-byte aligned; a
// kernel of lane width W uses 12 x W), link bound centres (3 x kLanes per link, aligned), the traversal stack (3 ints per entry) and
// the pairs in reach.
struct Candidate {
  double key;           // the smallest (centre distance / reach)^2 over the lanes in reach
  std::int32_t pair;    // index into Plan::pairs
  std::uint32_t lanes;  // the lanes in reach
};
struct Scratch {
  double* poses = nullptr;
  double* centers = nullptr;
  std::int32_t* stack = nullptr;
  Candidate* candidates = nullptr;  // Plan::pair_count of them
};

// Checks kLanes states (lane l reads lanes[l]): out[l] = 1 when the proxies of some pair come
// within its padding in that state. Same arithmetic in both, so the same answers.
void check_block_generic(const Plan& plan, const double* const* lanes, unsigned char* out, const Scratch& scratch);
void check_block_avx2(const Plan& plan, const double* const* lanes, unsigned char* out, const Scratch& scratch);
// Forward kinematics alone (tests): the poses of kLanes states into out[(link * 12 + e) * kLanes
// + lane] (rotation row-major, then translation).
void forward_kinematics_generic(const Plan& plan, const double* const* lanes, const Scratch& scratch, double* out);
void forward_kinematics_avx2(const Plan& plan, const double* const* lanes, const Scratch& scratch, double* out);
// sin and cos of kLanes values (tests: against the C library).
void sincos_generic(const double* x, double* s, double* c);
void sincos_avx2(const double* x, double* s, double* c);

}  // namespace bvh_collision::proxy_batch
