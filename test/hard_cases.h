// The named hard cases of triangle-pair collision (docs/design.md: touching counts,
// degenerate triangles are geometry): shared by the geometry tests (against CGAL's exact
// predicates) and the report's stability section (bench_stability, against CGAL and FCL).
#pragma once

#include <cmath>
#include <vector>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision::test {

inline Triangle triangle(const Vec3& a, const Vec3& b, const Vec3& c) { return Triangle{{a, b, c}}; }

struct NamedCase {
  const char* name;
  Triangle a, b;
  bool intersect;
};

inline std::vector<NamedCase> hard_cases() {
  const auto tri = triangle;
  const Vec3 o(0, 0, 0), x(1, 0, 0), y(0, 1, 0), z(0, 0, 1);
  const double ulp = std::nextafter(1.0, 2.0) - 1.0;
  return {
      {"coplanar_overlapping", tri(o, x, y), tri(Vec3(0.2, 0.2, 0), Vec3(2, 0.2, 0), Vec3(0.2, 2, 0)), true},
      {"coplanar_disjoint", tri(o, x, y), tri(Vec3(0.6, 0.6, 0), Vec3(2, 0.6, 0), Vec3(0.6, 2, 0)), false},
      {"coplanar_one_inside_other", tri(o, 4 * x, 4 * y), tri(Vec3(1, 1, 0), Vec3(1.5, 1, 0), Vec3(1, 1.5, 0)), true},
      {"coplanar_touching_edges", tri(o, x, y), tri(Vec3(0.5, 0.5, 0), Vec3(1, 1, 0), Vec3(0, 1, 0) + Vec3(1, 0, 0)), true},
      {"shared_edge", tri(o, x, y), tri(o, x, z), true},
      {"shared_edge_coplanar_opposite", tri(o, x, y), tri(o, x, -y), true},
      {"shared_vertex", tri(o, x, y), tri(o, -x + z, -y + z), true},
      {"vertex_touching_face", tri(o, x, y), tri(Vec3(0.25, 0.25, 0), Vec3(0.25, 0.25, 1), Vec3(1, 1, 1)), true},
      {"vertex_one_ulp_above_face", tri(o, x, y), tri(Vec3(0.25, 0.25, ulp), Vec3(0.25, 0.25, 1), Vec3(1, 1, 1)), false},
      {"edge_touching_edge", tri(o, x, z), tri(Vec3(0.5, -1, 0), Vec3(0.5, 1, 0), Vec3(0.5, 0, -1)), true},
      {"edge_crossing_edge_one_ulp_apart", tri(o, x, z), tri(Vec3(0.5, -1, -ulp), Vec3(0.5, 1, -ulp), Vec3(0.5, 0, -1)), false},
      {"parallel_planes_1e-12_apart", tri(o, x, y), tri(Vec3(0, 0, 1e-12), Vec3(1, 0, 1e-12), Vec3(0, 1, 1e-12)), false},
      {"sliver_aspect_1e6_crossing", tri(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 1e-6, 0)), tri(Vec3(0, 5e-7, -1), Vec3(0, 5e-7, 1), Vec3(0, 1, 0)), true},
      {"sliver_aspect_1e6_missing", tri(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 1e-6, 0)), tri(Vec3(0, 2e-6, -1), Vec3(0, 2e-6, 1), Vec3(0, 1, 0)), false},
      {"zero_area_segment_through_face", tri(Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 1)), tri(o, x, y), true},
      {"zero_area_segment_beside_face", tri(Vec3(0.6, 0.6, -1), Vec3(0.6, 0.6, 0), Vec3(0.6, 0.6, 1)), tri(o, x, y), false},
      {"zero_area_point_on_face", tri(Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 0), Vec3(0.2, 0.2, 0)), tri(o, x, y), true},
      {"zero_area_point_off_face", tri(Vec3(0.2, 0.2, ulp), Vec3(0.2, 0.2, ulp), Vec3(0.2, 0.2, ulp)), tri(o, x, y), false},
      {"zero_area_both_crossing_segments", tri(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 0)), tri(Vec3(0, -1, 0), Vec3(0, 1, 0), Vec3(0, 0.5, 0)), true},
      {"zero_area_both_skew_segments", tri(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 0)), tri(Vec3(0, -1, ulp), Vec3(0, 1, ulp), Vec3(0, 0.5, ulp)), false},
      {"zero_area_collinear_overlapping", tri(o, x, 0.5 * x), tri(0.75 * x, 2 * x, 1.5 * x), true},
      {"zero_area_collinear_disjoint", tri(o, x, 0.5 * x), tri(1.25 * x, 2 * x, 1.5 * x), false},
  };
}

}  // namespace bvh_collision::test
