// Basic geometric value types: vectors, rigid transforms, triangles.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace bvh_collision {

using Vec3 = Eigen::Vector3d;
using Mat3 = Eigen::Matrix3d;

// A rigid transform x -> R x + t, stored as 12 doubles (no homogeneous row).
struct Transform {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();

  static Transform Identity() { return {}; }
  static Transform Translation(const Vec3& t) { return {Mat3::Identity(), t}; }

  // Written out: GCC does not inline Eigen's assignment loop for R * p + t (a call in the proxy
  // walks' innermost loop). The sums are grouped as Eigen's SSE2
  // product groups them (rows 0-1 as a packet, row 2 alone), so every result is bit for bit the
  // same as before.
  Vec3 operator*(const Vec3& p) const {
    return {(R(0, 0) * p[0] + R(0, 1) * p[1]) + R(0, 2) * p[2] + t[0], (R(1, 0) * p[0] + R(1, 1) * p[1]) + R(1, 2) * p[2] + t[1],
            R(2, 0) * p[0] + (R(2, 1) * p[1] + R(2, 2) * p[2]) + t[2]};
  }
  Transform operator*(const Transform& o) const { return {R * o.R, R * o.t + t}; }
  Transform inverse() const { return {R.transpose(), -(R.transpose() * t)}; }
};

// Finite, with a proper rotation (orthonormal to 1e-6, determinant +1): what a pose from a user
// or a message must be before any query uses it.
inline bool is_rigid(const Transform& pose) {
  return pose.R.allFinite() && pose.t.allFinite() && (pose.R.transpose() * pose.R).isApprox(Mat3::Identity(), 1e-6) &&
         pose.R.determinant() > 0;
}

// The pose of b in a's frame, a^-1 * b, computed as R_a^T (t_b - t_a): two poses far from the
// origin with the same translation cancel exactly, so results do not depend on where the scene is.
inline Transform relative_transform(const Transform& a, const Transform& b) {
  return {a.R.transpose() * b.R, a.R.transpose() * (b.t - a.t)};
}

struct Triangle {
  Vec3 v[3];
  const Vec3& operator[](int i) const { return v[i]; }
  Vec3& operator[](int i) { return v[i]; }
};

}  // namespace bvh_collision
