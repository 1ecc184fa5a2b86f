#include "bvh_collision/geometry/predicates.h"

#include "bvh_collision/geometry/detail/filtered_predicates.h"

#include <array>
#include <cmath>

namespace bvh_collision {
namespace {

// Error-free transformations (Knuth's two-sum, FMA two-product): a op b = x + y exactly.
inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a;
  const double av = x - bv;
  y = (a - av) + (b - bv);
}

inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

// An exact sum of doubles as a non-overlapping expansion, smallest component first (Shewchuk's
// GROW-EXPANSION with zero elimination). The sign of the sum is the sign of the last component.
class ExactSum {
 public:
  void add(double b) {
    double q = b;
    int k = 0;
    for (int i = 0; i < n_; ++i) {
      double sum, err;
      two_sum(q, e_[i], sum, err);
      if (err != 0.0) e_[k++] = err;
      q = sum;
    }
    if (q != 0.0) e_[k++] = q;
    n_ = k;
  }
  // Adds x * y * z exactly (x*y = p + r exactly, then p*z and r*z each split in two).
  void add_product(double x, double y, double z) {
    double p, r, h, l;
    two_product(x, y, p, r);
    two_product(p, z, h, l);
    add(h);
    add(l);
    two_product(r, z, h, l);
    add(h);
    add(l);
  }
  void add_product(double x, double y) {
    double h, l;
    two_product(x, y, h, l);
    add(h);
    add(l);
  }
  int sign() const { return n_ == 0 ? 0 : (e_[n_ - 1] > 0.0 ? 1 : -1); }

 private:
  // An expansion of k doubles never needs more than k components; 256 covers orient3d's 192.
  std::array<double, 256> e_{};
  int n_ = 0;
};

// a - b as an exact two-term expansion.
struct Diff {
  double hi, lo;
};
inline Diff exact_diff(double a, double b) {
  Diff d;
  d.hi = a - b;
  const double bv = a - d.hi;
  const double av = d.hi + bv;
  d.lo = (a - av) + (bv - b);
  return d;
}

// Adds sign * x * y * z where each factor is a two-term expansion (8 triple products).
void add_triple(ExactSum& sum, double sign, const Diff& x, const Diff& y, const Diff& z) {
  for (double xi : {x.hi, x.lo}) {
    if (xi == 0.0) continue;
    for (double yi : {y.hi, y.lo}) {
      if (yi == 0.0) continue;
      for (double zi : {z.hi, z.lo}) {
        if (zi != 0.0) sum.add_product(sign * xi, yi, zi);
      }
    }
  }
}

}  // namespace

namespace detail {

int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const Diff adx = exact_diff(a.x(), d.x()), ady = exact_diff(a.y(), d.y()), adz = exact_diff(a.z(), d.z());
  const Diff bdx = exact_diff(b.x(), d.x()), bdy = exact_diff(b.y(), d.y()), bdz = exact_diff(b.z(), d.z());
  const Diff cdx = exact_diff(c.x(), d.x()), cdy = exact_diff(c.y(), d.y()), cdz = exact_diff(c.z(), d.z());
  ExactSum sum;
  // adz (bdx cdy - cdx bdy) + bdz (cdx ady - adx cdy) + cdz (adx bdy - bdx ady)
  add_triple(sum, 1.0, adz, bdx, cdy);
  add_triple(sum, -1.0, adz, cdx, bdy);
  add_triple(sum, 1.0, bdz, cdx, ady);
  add_triple(sum, -1.0, bdz, adx, cdy);
  add_triple(sum, 1.0, cdz, adx, bdy);
  add_triple(sum, -1.0, cdz, bdx, ady);
  return sum.sign();
}

int orient2d_exact(double ax, double ay, double bx, double by, double cx, double cy) {
  const Diff acx = exact_diff(ax, cx), acy = exact_diff(ay, cy);
  const Diff bcx = exact_diff(bx, cx), bcy = exact_diff(by, cy);
  ExactSum sum;
  for (double x : {acx.hi, acx.lo}) {
    for (double y : {bcy.hi, bcy.lo}) sum.add_product(x, y);
  }
  for (double x : {acy.hi, acy.lo}) {
    for (double y : {bcx.hi, bcx.lo}) sum.add_product(-x, y);
  }
  return sum.sign();
}

}  // namespace detail

int projection_axis(const Vec3& a, const Vec3& b, const Vec3& c) {
  int dominant = 0;
  ((b - a).cross(c - a)).cwiseAbs().maxCoeff(&dominant);
  if (orient2d(a, b, c, dominant) != 0) return dominant;
  for (int k = 0; k < 3; ++k) {
    if (k != dominant && orient2d(a, b, c, k) != 0) return k;
  }
  return -1;
}

}  // namespace bvh_collision

namespace bvh_collision {

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) { return detail::orient3d_filtered(a, b, c, d); }
int orient2d(const Vec3& a, const Vec3& b, const Vec3& c, int drop) { return detail::orient2d_filtered(a, b, c, drop); }

TrianglePlane TrianglePlane::of(const Vec3& t0, const Vec3& t1, const Vec3& t2) { return detail::plane_of(t0, t1, t2); }
int TrianglePlane::side(const Vec3& v) const { return detail::plane_side(*this, v); }
bool TrianglePlane::separates(const Vec3& a, const Vec3& b, const Vec3& c) const {
  return detail::plane_separates(*this, a, b, c);
}

}  // namespace bvh_collision
