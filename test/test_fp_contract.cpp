// The floating-point contract of the public headers (geometry/predicates.h): a translation unit
// compiled with FMA contraction (fp_contract_probe.cpp: -ffp-contract=fast -mfma) gets the same
// exact signs as CGAL on near-degenerate and exactly degenerate input, because no filtered
// arithmetic is compiled in the caller's unit. This test's own unit is built as usual.
#include <gtest/gtest.h>

#include <random>

#include "cgal_oracle.h"
#include "robot_data.h"

namespace bvh_collision::test {

int probe_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
int probe_orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop);
int probe_plane_side(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);
bool probe_triangles_intersect(const Triangle& a, const Triangle& b);

namespace {

std::mt19937_64& rng() {
  static std::mt19937_64 r(31);
  return r;
}

Vec3 random_point(double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng()), u(rng()), u(rng())};
}

// d on the plane of a, b, c up to the rounding of its coordinates: determinants far below the
// products they are made of, where a filter's error bound is all that decides.
Vec3 nearly_on_plane(const Vec3& a, const Vec3& b, const Vec3& c) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  return a + u(rng()) * (b - a) + u(rng()) * (c - a);
}

// Exactly coplanar: small integers times a power of two, offset far from the origin.
Vec3 grid_point(double offset) {
  std::uniform_int_distribution<int> k(-8, 8);
  return Vec3(offset + k(rng()) * 0.125, offset + k(rng()) * 0.125, 0.0);
}

TEST(FloatingPointContract, PredicatesUnderFmaContractionEqualCgal) {
  if (!__builtin_cpu_supports("fma")) GTEST_SKIP() << "this CPU has no FMA: the probe was not run";
  int zero_signs = 0;
  for (int i = 0; i < test::sized(50000); ++i) {
    const double scale = i % 3 == 0 ? 1e-3 : (i % 3 == 1 ? 1.0 : 1e3);
    Vec3 a = random_point(scale), b = random_point(scale), c = random_point(scale), d = nearly_on_plane(a, b, c);
    if (i % 4 == 0) a = grid_point(1e4), b = grid_point(1e4), c = grid_point(1e4), d = grid_point(1e4);
    const int cgal = cgal_orient3d(a, b, c, d);
    zero_signs += cgal == 0;
    ASSERT_EQ(probe_orient3d(a, b, c, d), cgal) << "case " << i;
    const int side = probe_plane_side(a, b, c, d);
    // TrianglePlane's side is the sign of det[b - a, c - a, d - a], the opposite of orient3d's.
    ASSERT_TRUE(side == 0 || side == -cgal) << "a certain side must be the exact one, case " << i;
    for (int k = 0; k < 3; ++k) {
      const Vec3 e = a + 0.37 * (b - a);  // nearly collinear with a and b
      ASSERT_EQ(probe_orient2d(a, b, e, k), cgal_orient2d(a, b, e, k)) << "case " << i << " axis " << k;
    }
    const Triangle t{{a, b, c}}, u{{d, a + 0.5 * (b - a), d + (c - a)}};
    ASSERT_EQ(probe_triangles_intersect(t, u), cgal_triangles_intersect(t, u)) << "case " << i;
  }
  EXPECT_GT(zero_signs, test::sized(50000) / 50) << "exactly degenerate cases must be among those tested";
}

}  // namespace
}  // namespace bvh_collision::test
