#include "server/core/sim/reach_ik.h"

#include <algorithm>

#include <Eigen/Dense>

namespace modskill {
namespace {

constexpr int kIterations = 300;
constexpr double kDamping = 0.05;        // lambda of DLS: keeps steps finite near singular poses (m)
constexpr double kPostureGain = 0.1;     // share of the way back to the start taken in the null space per step
constexpr double kMaxStep = 0.2;         // rad, largest change of the moved hinges per iteration
constexpr double kFiniteDifference = 1e-6;
constexpr double kTolerance = 1e-4;      // m

// Forward kinematics for positions only, into preallocated buffers.
class BodyPositions {
 public:
  explicit BodyPositions(const HumanoidSpec& spec)
      : spec_(spec), zeros_(spec.num_hinges(), 0.0), pos_(spec.num_bodies()), rot_(spec.num_bodies()),
        vel_(spec.num_bodies()), ang_vel_(spec.num_bodies()) {}
  const Vec3& Of(const RootState& root, const std::vector<double>& dof_pos, int body) {
    ComputeBodyKinematics(spec_, root, dof_pos.data(), zeros_.data(), pos_.data(), rot_.data(), vel_.data(),
                          ang_vel_.data());
    return pos_[body];
  }

 private:
  const HumanoidSpec& spec_;
  std::vector<double> zeros_;
  std::vector<Vec3> pos_;
  std::vector<Quat> rot_;
  std::vector<Vec3> vel_, ang_vel_;
};

}  // namespace

ReachIkResult SolveReachIk(const HumanoidSpec& spec, const RootState& root, const std::vector<double>& dof_pos,
                           int body, const std::vector<int>& moved_bodies, const Vec3& target) {
  std::vector<int> hinges;
  for (int b : moved_bodies) {
    for (int k = 0; k < 3; ++k) hinges.push_back(3 * (b - 1) + k);
  }
  const int n = static_cast<int>(hinges.size());
  BodyPositions positions(spec);
  ReachIkResult result{dof_pos, 0.0};
  std::vector<double>& q = result.dof_pos;
  Eigen::MatrixXd jacobian(3, n);
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    const Vec3 at = positions.Of(root, q, body);
    const Vec3 error = target - at;
    if (error.norm() < kTolerance) break;
    for (int j = 0; j < n; ++j) {
      q[hinges[j]] += kFiniteDifference;
      jacobian.col(j) = (positions.Of(root, q, body) - at) / kFiniteDifference;
      q[hinges[j]] -= kFiniteDifference;
    }
    // dq = J^T (J J^T + lambda^2 I)^-1 e, plus (I - J^+ J) times a pull toward the start.
    const Eigen::Matrix3d gram = jacobian * jacobian.transpose() + kDamping * kDamping * Eigen::Matrix3d::Identity();
    const Eigen::MatrixXd pseudo_inverse = jacobian.transpose() * gram.inverse();
    Eigen::VectorXd pull(n);
    for (int j = 0; j < n; ++j) pull[j] = kPostureGain * (dof_pos[hinges[j]] - q[hinges[j]]);
    Eigen::VectorXd step = pseudo_inverse * error + (pull - pseudo_inverse * (jacobian * pull));
    if (step.norm() > kMaxStep) step *= kMaxStep / step.norm();
    for (int j = 0; j < n; ++j) {
      const BodySpec& moved = spec.body(hinges[j] / 3 + 1);
      const int k = hinges[j] % 3;
      q[hinges[j]] = std::clamp(q[hinges[j]] + step[j], moved.range_low[k], moved.range_high[k]);
    }
  }
  result.distance = (target - positions.Of(root, q, body)).norm();
  return result;
}

}  // namespace modskill
