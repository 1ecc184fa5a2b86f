// Compiled with -ffp-contract=fast -mfma (CMakeLists.txt): a downstream package's translation unit
// that includes the public headers and calls the predicates, as test_fp_contract checks.
#include "bvh_collision/bvh/bvh.h"
#include "bvh_collision/geometry/intersection.h"
#include "bvh_collision/geometry/predicates.h"

namespace bvh_collision::test {

int probe_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) { return orient3d(a, b, c, d); }
int probe_orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop) { return orient2d(a, b, c, drop); }
int probe_plane_side(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return TrianglePlane::of(a, b, c).side(d);
}
bool probe_triangles_intersect(const Triangle& a, const Triangle& b) { return triangles_intersect(a, b); }

}  // namespace bvh_collision::test
