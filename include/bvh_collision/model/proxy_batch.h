// Batches of boolean self checks on the link proxies, vectorised over states:
// states in the lanes of one kernel (src/model/proxy_batch_kernel.h) that does their forward
// kinematics, the bounding-sphere broad phase, the clearance grids and one proxy tree traversal
// for all lanes. The kernel is built twice, for SSE2 (two lanes; any x86-64, the default -O2
// build) and for AVX2 (four lanes), and the AVX2 one is taken at run time where the CPU has it;
// both round alike (no fused multiply-add), so they answer alike (test_proxy_batch).
//
// Answers keep the proxies' contract (narrowphase/link_proxy.h): a state whose proxies are apart in
// every checked pair is free (exact distance > padding); one reported colliding has some pair
// within padding + level. CollisionChecker::check_batch takes this path for self checks at a
// tolerance some proxy level fits.
#pragma once

#include <cstddef>
#include <vector>

#include "bvh_collision/geometry/simd_path.h"
#include "bvh_collision/model/detail/proxy_batch_plan.h"

namespace bvh_collision {

class PairClearance;
class RobotCollisionModel;
struct ProxyLevel;

class ProxyBatch {
 public:
  ProxyBatch() = default;
  // The flat form of `level`'s proxies with the model's kinematics, bounds and checked pairs
  // (those `clearance` has a grid for marked). Empty (unusable) when the model holds a joint kind
  // the kernel does not compute.
  ProxyBatch(const RobotCollisionModel& model, const PairClearance& clearance, const ProxyLevel& level);

  // No pair for the lanes (none checked, or the level leaves every pair to the exact test:
  // ProxyLevel::exact_pairs): nothing to gain from the kernel.
  bool empty() const { return pairs_.empty(); }
  // out[i] = 1 when state i (states row-major, `count` of them) has proxies within padding in
  // some checked pair: check_self's answer at a tolerance this level fits (the broad phase
  // reaches as far as check_self's, which no tolerance grows). Runs on the calling thread. kAvx2
  // on a CPU without it throws std::runtime_error.
  // `clearance`: the grids the batch was built with.
  void check(const PairClearance& clearance, const double* states, std::size_t count, char* out,
             SimdPath path = SimdPath::kAuto) const;
  // The kernel's link poses for up to four states (tests): per link 12 values (rotation
  // row-major, translation) per state, as poses[((link * 12) + e) * 4 + lane]; zero for the links
  // the kinematics plan does not compute.
  std::vector<double> poses(const double* states, std::size_t count, SimdPath path = SimdPath::kAuto) const;
  // The kernel's sine and cosine of four values (tests).
  static void sincos(const double* x, double* s, double* c, SimdPath path = SimdPath::kAuto);

 private:
  proxy_batch::Plan plan(const PairClearance* clearance) const;

  std::vector<proxy_batch::Step> steps_;
  std::vector<proxy_batch::Link> links_;
  std::vector<proxy_batch::Sphere> spheres_;
  std::vector<proxy_batch::Pair> pairs_;
  int root_ = 0;
  int stride_ = 0;
  int stack_capacity_ = 0;
};

}  // namespace bvh_collision
