#include "server/core/env/strike_task.h"

#include <algorithm>
#include <cmath>

#include "server/core/sim/heading_frame.h"
#include "server/core/sim/mjcf_builder.h"

namespace modskill {
namespace {

Vec3 Read3(const double* v) { return Vec3(v[0], v[1], v[2]); }

// How far the target at free-joint qpos `q` has tipped: 1 - up . u_target (0 standing, 1 lying).
double TipOf(const double* q) {
  const double up = (Quat(q[3], q[4], q[5], q[6]).normalized() * Vec3::UnitZ()).z();
  return std::clamp(1.0 - up, 0.0, 1.0);
}

// Tipped past this, the target counts as down: the approach term is paid in full and a steered
// base motion turns away from it.
constexpr double kDownTip = 0.5;

void Write3(const Vec3& v, float* out) {
  out[0] = static_cast<float>(v.x());
  out[1] = static_cast<float>(v.y());
  out[2] = static_cast<float>(v.z());
}

}  // namespace

void StrikeTask::DrawGoal(const HumanoidState& sim, std::mt19937_64& rng) {
  const double distance = std::uniform_real_distribution<double>(kMinDistance, kMaxDistance)(rng);
  const double bearing = std::uniform_real_distribution<double>(-kMaxBearing, kMaxBearing)(rng);
  yaw_ = std::uniform_real_distribution<double>(-M_PI, M_PI)(rng);
  position_ = HeadingGroundPointToWorld(sim.body_pos[0], sim.body_rot[0],
                                       Vec3(distance * std::cos(bearing), distance * std::sin(bearing), 0));
  position_.z() = kStrikeTargetHalfExtents[2];
}

void StrikeTask::Reset(const HumanoidState& sim, mjData* data, std::mt19937_64& rng) {
  StartGoal(sim, rng);
  double* qpos = data->qpos + context_->target_qpos;
  qpos[0] = position_.x();
  qpos[1] = position_.y();
  qpos[2] = position_.z();
  const Quat turn(Eigen::AngleAxisd(yaw_, Vec3::UnitZ()));
  qpos[3] = turn.w();
  qpos[4] = turn.x();
  qpos[5] = turn.y();
  qpos[6] = turn.z();
  std::fill_n(data->qvel + context_->target_qvel, 6, 0.0);
}

void StrikeTask::Reward(const HumanoidState& sim, const mjData* data, float* terms) {
  const double* q = data->qpos + context_->target_qpos;
  const double tip = TipOf(q);
  terms[0] = static_cast<float>(kTipWeight * tip);
  Vec3 to_target = Read3(q) - sim.body_pos[0];
  to_target.z() = 0;
  const double distance = to_target.norm();
  double approach = 1;
  if (distance > kNearDistance && tip < kDownTip) {
    const double toward = sim.body_vel[0].dot(to_target / distance);
    const double shortfall = std::max(0.0, kApproachSpeed - toward);
    approach = toward > 0 ? std::exp(-4 * shortfall * shortfall) : 0;
  }
  terms[1] = static_cast<float>(kApproachWeight * approach);
}

bool StrikeTask::Failed(const mjData* data) const {
  const double* q = data->qpos + context_->target_qpos;
  const Vec3 root = Read3(data->qpos);
  if (!((Read3(q) - root).norm() < kLostDistance)) return true;
  const int target = context_->target_geom;
  for (int c = 0; c < data->ncon; ++c) {
    const mjContact& contact = data->contact[c];
    const int other = contact.geom1 == target ? contact.geom2 : contact.geom2 == target ? contact.geom1 : -1;
    if (other >= 0 && !context_->may_touch_target[other]) return true;
  }
  return false;
}

Vec3 StrikeTask::GoalBearing(const HumanoidState& sim, const mjData* data) const {
  const double* q = data->qpos + context_->target_qpos;
  Vec3 to_target = Read3(q) - sim.body_pos[0];
  to_target.z() = 0;
  const double distance = to_target.norm();
  if (distance < 1e-9) return to_target;
  const Vec3 left = Vec3(-to_target.y(), to_target.x(), 0.0) / distance;
  // Down: turn left, away from where it lies, rather than walk over it.
  if (TipOf(q) > kDownTip) return left;
  return to_target + kHandOffset * left;
}

void StrikeTask::WriteGoal(const HumanoidState& sim, const mjData* data, float* goal) const {
  const double* q = data->qpos + context_->target_qpos;
  const double* v = data->qvel + context_->target_qvel;
  const Quat to_heading = InverseHeadingRotation(sim.body_rot[0]);
  Write3(to_heading * (Read3(q) - sim.body_pos[0]), goal);
  WriteTanNorm(to_heading * Quat(q[3], q[4], q[5], q[6]).normalized(), goal + 3);
  // A free joint's qvel: linear velocity in the world frame, angular velocity in the body's.
  Write3(to_heading * Read3(v), goal + 9);
  Write3(to_heading * (Quat(q[3], q[4], q[5], q[6]).normalized() * Read3(v + 3)), goal + 12);
}

}  // namespace modskill
