// A column of three doubles held as rows 0-1 in one SSE2 register and row 2 alone (the baseline
// x86-64 has two lanes), for products of poses written out: at -O2 GCC leaves Eigen's small
// products as calls and keeps loops over three rows, twice the work. Lane arithmetic
// rounds as scalar arithmetic does and the sums keep one order (row r: a(r,0) b0 + a(r,1) b1 +
// a(r,2) b2), so the results are the scalar products bit for bit (and the batch kernel's,
// model/proxy_batch_kernel.h).
#pragma once

#include <cstring>

#include "bvh_collision/geometry/types.h"

namespace bvh_collision {

typedef double TwoRows __attribute__((vector_size(16)));

struct SplitColumn {
  TwoRows top;
  double bottom;
};

[[gnu::always_inline]] inline SplitColumn load_column(const double* col) {
  SplitColumn c;
  std::memcpy(&c.top, col, sizeof c.top);
  c.bottom = col[2];
  return c;
}

[[gnu::always_inline]] inline void store_column(const SplitColumn& c, double* col) {
  std::memcpy(col, &c.top, sizeof c.top);
  col[2] = c.bottom;
}

// The rotation a's columns times the column b.
[[gnu::always_inline]] inline SplitColumn times(const SplitColumn* a, const double* b) {
  return {a[0].top * b[0] + a[1].top * b[1] + a[2].top * b[2], a[0].bottom * b[0] + a[1].bottom * b[1] + a[2].bottom * b[2]};
}

[[gnu::always_inline]] inline void load_rotation(const Mat3& r, SplitColumn* columns) {
  for (int c = 0; c < 3; ++c) columns[c] = load_column(r.col(c).data());
}

// pose * p, into out (the same bits as pose.R(i,0) p0 + pose.R(i,1) p1 + pose.R(i,2) p2 + pose.t(i)).
[[gnu::always_inline]] inline void transform_point(const Transform& pose, const double* p, double* out) {
  SplitColumn r[3];
  load_rotation(pose.R, r);
  SplitColumn q = times(r, p);
  const SplitColumn t = load_column(pose.t.data());
  q.top += t.top;
  q.bottom += t.bottom;
  store_column(q, out);
}

}  // namespace bvh_collision
