// The tolerance policy (narrowphase/tolerance_policy.h).
#include "bvh_collision/narrowphase/tolerance_policy.h"

namespace bvh_collision {

double proxy_error(double level, Counterpart other) { return other == Counterpart::kLink ? level : level / 2; }

ProxyUse proxy_use(const ToleranceQuestion& q) {
  ProxyUse use;
  if (!(q.tolerance > 0.0) || !q.boolean || !q.solids) return use;  // exact: the proxies only prune
  if (q.other == Counterpart::kOctree && !q.octree_field) return use;
  // The largest level whose error against the counterpart fits the tolerance.
  use.decide_up_to = q.other == Counterpart::kLink ? q.tolerance : 2.0 * q.tolerance;
  return use;
}

bool interval_within_tolerance(double level, Counterpart other, double growth, double tolerance) {
  return proxy_error(level, other) + growth <= tolerance;
}

}  // namespace bvh_collision
