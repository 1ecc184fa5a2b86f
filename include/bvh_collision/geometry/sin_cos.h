// Sine and cosine of one angle together, for forward kinematics: the C library's sincos is a
// large part of a pose (docs/performance.md); this one is a third of its cost, with no
// call and no branch but the quadrant's, and the batch kernel (model/proxy_batch_kernel.h)
// evaluates the same constants and the same operations in its lanes, so both give the same bits.
//
// x = k pi/2 + r with k = round(2x/pi) and |r| <= pi/4 (+ rounding); pi/2 in three parts: hi (26
// significant bits) and mid (27) sum to the double nearest pi/2, and lo = pi/2 - (hi + mid) to
// double precision. For |k| <= 2^20, k hi and k mid are exact, x - k hi is exact (Sterbenz), and
// r carries at most ~3 ulp of r plus |k| 1e-32. Taylor series through r^17 (sine) and r^18
// (cosine): the first omitted terms are below 1e-19 at |r| = 0.786, and Horner's rounding adds a
// few ulp. So each result is within ~5e-16 of exact for |x| <= 1.6e6 (test_geometry checks 1e-15
// against the C library); beyond that, or not finite, the C library's answers.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

namespace bvh_collision {

namespace sin_cos_constants {
constexpr double kTwoOverPi = 0.6366197723675814;
constexpr double kPiOver2Hi = 1.5707963109016418;
constexpr double kPiOver2Mid = 1.5893254712295857e-08;
constexpr double kPiOver2Lo = 6.123233995736766e-17;
constexpr double kRoundShift = 6755399441055744.0;  // 1.5 * 2^52: y + shift holds round(y) in its low bits
constexpr double kReducedRange = 1.6e6;
// Horner over 1/n!, signs alternating: sine n = 17, 15, ..., 3, cosine n = 18, 16, ..., 2.
constexpr double kSine[] = {1.0 / 355687428096000.0, -1.0 / 1307674368000.0, 1.0 / 6227020800.0, -1.0 / 39916800.0,
                            1.0 / 362880.0, -1.0 / 5040.0, 1.0 / 120.0, -1.0 / 6.0};
constexpr double kCosine[] = {1.0 / 6402373705728000.0, -1.0 / 20922789888000.0, 1.0 / 87178291200.0,
                              -1.0 / 479001600.0, 1.0 / 3628800.0, -1.0 / 40320.0, 1.0 / 720.0, -1.0 / 24.0, 0.5};
}  // namespace sin_cos_constants

inline void sin_cos(double x, double& s, double& c) {
  namespace k = sin_cos_constants;
  if (!(std::abs(x) <= k::kReducedRange)) {
    s = std::sin(x), c = std::cos(x);
    return;
  }
  const double shifted = x * k::kTwoOverPi + k::kRoundShift;
  std::uint64_t quadrant;
  std::memcpy(&quadrant, &shifted, sizeof quadrant);
  const double n = shifted - k::kRoundShift;
  const double r = ((x - n * k::kPiOver2Hi) - n * k::kPiOver2Mid) - n * k::kPiOver2Lo;
  const double r2 = r * r;
  // Horner written out (at -O2 GCC keeps the loops, several times slower).
  const double ps = ((((((k::kSine[0] * r2 + k::kSine[1]) * r2 + k::kSine[2]) * r2 + k::kSine[3]) * r2 + k::kSine[4]) * r2 +
                      k::kSine[5]) * r2 + k::kSine[6]) * r2 + k::kSine[7];
  const double sin_r = r + r * r2 * ps;
  const double pc = (((((((k::kCosine[0] * r2 + k::kCosine[1]) * r2 + k::kCosine[2]) * r2 + k::kCosine[3]) * r2 +
                        k::kCosine[4]) * r2 + k::kCosine[5]) * r2 + k::kCosine[6]) * r2 + k::kCosine[7]) * r2 + k::kCosine[8];
  const double cos_r = 1.0 - r2 * pc;
  // Quadrant k mod 4: (sin, cos) = (s, c), (c, -s), (-s, -c), (-c, s).
  const double s0 = (quadrant & 1) ? cos_r : sin_r;
  const double c0 = (quadrant & 1) ? sin_r : cos_r;
  s = (quadrant & 2) ? -s0 : s0;
  c = ((quadrant + 1) & 2) ? -c0 : c0;
}

}  // namespace bvh_collision
