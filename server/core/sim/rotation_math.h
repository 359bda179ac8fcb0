// Rotation helpers shared by motion processing, observations and rewards.
// World frame is z-up; the humanoid faces +x at rest with its left along +y.
#ifndef MODSKILL_SERVER_CORE_SIM_ROTATION_MATH_H_
#define MODSKILL_SERVER_CORE_SIM_ROTATION_MATH_H_

#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace modskill {

using Vec3 = Eigen::Vector3d;
using Quat = Eigen::Quaterniond;
using Mat3 = Eigen::Matrix3d;

// The yaw (rad, about +z, from +x) of the horizontal projection of q's forward axis.
inline double HeadingAngle(const Quat& q) {
  const Vec3 forward = q * Vec3::UnitX();
  return std::atan2(forward.y(), forward.x());
}

// Yaw-only rotation that carries +x onto the horizontal projection of q's forward axis.
inline Quat HeadingRotation(const Quat& q) { return Quat(Eigen::AngleAxisd(HeadingAngle(q), Vec3::UnitZ())); }

// Inverse of HeadingRotation: rotates world vectors into the agent's heading frame.
inline Quat InverseHeadingRotation(const Quat& q) { return HeadingRotation(q).conjugate(); }

// Tangent-normal encoding of a rotation (6 numbers): the rotated x axis and z axis.
// Continuous, unlike Euler angles or quaternions with their double cover.
inline void WriteTanNorm(const Quat& q, float* out) {
  const Mat3 r = q.toRotationMatrix();
  out[0] = static_cast<float>(r(0, 0));
  out[1] = static_cast<float>(r(1, 0));
  out[2] = static_cast<float>(r(2, 0));
  out[3] = static_cast<float>(r(0, 2));
  out[4] = static_cast<float>(r(1, 2));
  out[5] = static_cast<float>(r(2, 2));
}

// Rotation angle in [0, pi] of q.
inline double RotationAngle(const Quat& q) {
  const double w = std::min(1.0, std::abs(q.w()));
  return 2.0 * std::acos(w);
}

// Rotation vector (axis * angle) of q, shortest path.
inline Vec3 RotationVector(const Quat& q_in) {
  Quat q = q_in.w() < 0 ? Quat(-q_in.w(), -q_in.x(), -q_in.y(), -q_in.z()) : q_in;
  const double sin_half = q.vec().norm();
  if (sin_half < 1e-12) return 2.0 * q.vec();
  const double angle = 2.0 * std::atan2(sin_half, q.w());
  return q.vec() * (angle / sin_half);
}

inline Quat QuatFromRotationVector(const Vec3& v) {
  const double angle = v.norm();
  if (angle < 1e-12) return Quat(1.0, 0.5 * v.x(), 0.5 * v.y(), 0.5 * v.z()).normalized();
  return Quat(Eigen::AngleAxisd(angle, v / angle));
}

// World-frame angular velocity that takes q0 to q1 in dt seconds.
inline Vec3 AngularVelocity(const Quat& q0, const Quat& q1, double dt) {
  return RotationVector(q1 * q0.conjugate()) / dt;
}

// Intrinsic x-y-z Euler angles: R = Rx(a) * Ry(b) * Rz(c).
inline Quat QuatFromIntrinsicXyz(double a, double b, double c) {
  return Quat(Eigen::AngleAxisd(a, Vec3::UnitX())) * Quat(Eigen::AngleAxisd(b, Vec3::UnitY())) *
         Quat(Eigen::AngleAxisd(c, Vec3::UnitZ()));
}

// Inverse of QuatFromIntrinsicXyz; b in [-pi/2, pi/2].
inline Vec3 IntrinsicXyzFromQuat(const Quat& q) {
  const Mat3 r = q.normalized().toRotationMatrix();
  const double b = std::asin(std::clamp(r(0, 2), -1.0, 1.0));
  double a, c;
  if (std::abs(r(0, 2)) < 1.0 - 1e-9) {
    a = std::atan2(-r(1, 2), r(2, 2));
    c = std::atan2(-r(0, 1), r(0, 0));
  } else {  // gimbal lock: only a + c (or a - c) is defined; put it all on a.
    a = std::atan2(r(2, 1), r(1, 1));
    c = 0.0;
  }
  return Vec3(a, b, c);
}

// The hinges of a body. Each non-root body has three, named _x, _y, _z after PHC's y-up frame,
// whose ranges they keep (the knee bends about PHC's x). In the z-up simulation frame those axes
// are +y, +z and +x. MuJoCo composes them in that order: R = R(y, a) * R(z, b) * R(x, c).
// Equivalently R = P * XYZ(a, b, c) * P^T with P the y-up -> z-up map, so the first angle
// (the knee's flexion) has the full range of an intrinsic x-y-z decomposition.
inline Vec3 HingeAxis(int k) {
  static const Vec3 kAxes[3] = {Vec3::UnitY(), Vec3::UnitZ(), Vec3::UnitX()};
  return kAxes[k];
}

inline Quat HingeRotation(double a, double b, double c) {
  return Quat(Eigen::AngleAxisd(a, HingeAxis(0))) * Quat(Eigen::AngleAxisd(b, HingeAxis(1))) *
         Quat(Eigen::AngleAxisd(c, HingeAxis(2)));
}

// Inverse of HingeRotation (the middle angle in [-pi/2, pi/2]).
inline Vec3 HingeAngles(const Quat& q) {
  // P^T q P expresses q in the y-up frame, where the hinges are x, y, z.
  const Quat p_conj(0.5, -0.5, -0.5, -0.5);  // P = rotation (x,y,z) -> (z,x,y) is quat (0.5, 0.5, 0.5, 0.5)
  const Quat p(0.5, 0.5, 0.5, 0.5);
  return IntrinsicXyzFromQuat(p_conj * q.normalized() * p);
}

// Shortest rotation taking direction `from` onto direction `to`.
inline Quat RotationBetween(const Vec3& from, const Vec3& to) {
  return Quat::FromTwoVectors(from, to);
}

// Wraps an angle difference to (-pi, pi].
inline double WrapAngle(double a) {
  a = std::fmod(a + M_PI, 2.0 * M_PI);
  if (a < 0) a += 2.0 * M_PI;
  return a - M_PI;
}

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_ROTATION_MATH_H_
