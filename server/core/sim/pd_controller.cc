#include "server/core/sim/pd_controller.h"

#include <algorithm>
#include <cmath>

namespace modskill {

PdController::PdController(const HumanoidModel& humanoid)
    : humanoid_(humanoid),
      model_(humanoid.model()),
      dense_mass_(humanoid.options().pd_mode == PdMode::kStablePd ? humanoid.model()->nv * humanoid.model()->nv : 0),
      system_(humanoid.options().pd_mode == PdMode::kStablePd ? humanoid.model()->nv : 0,
              humanoid.options().pd_mode == PdMode::kStablePd ? humanoid.model()->nv : 0),
      rhs_(system_.rows()),
      acceleration_(system_.rows()),
      solver_(system_.rows()) {}

double PdController::Step(const double* targets, mjData* data) {
  return humanoid_.options().pd_mode == PdMode::kStablePd ? StepStablePd(targets, data)
                                                          : StepPositionImplicit(targets, data);
}

double PdController::StepPositionImplicit(const double* targets, mjData* data) {
  const mjModel* m = model_;
  const int hinges = humanoid_.num_hinges(), qvel0 = humanoid_.hinge_qvel_start();
  const std::vector<double>& kd = humanoid_.kd();
  for (int h = 0; h < hinges; ++h) data->ctrl[h] = targets[h];
  double power = 0;
  const int substeps = humanoid_.options().substeps;
  for (int s = 0; s < substeps; ++s) {
    mj_step(m, data);
    for (int h = 0; h < hinges; ++h) {
      const double qdot = data->qvel[qvel0 + h];
      power += std::abs((data->actuator_force[h] - kd[h] * qdot) * qdot);
    }
  }
  return power / substeps;
}

// Tan, Liu, Turk 2011: tau = -kp (q + dt qdot - target) - kd (qdot + dt qddot), with qddot
// from (M + dt Kd) qddot = -bias + passive + the PD terms. Contacts are left out of the
// prediction, as in the paper.
double PdController::StepStablePd(const double* targets, mjData* data) {
  const mjModel* m = model_;
  const int nv = m->nv, hinges = humanoid_.num_hinges();
  const int qpos0 = humanoid_.hinge_qpos_start(), qvel0 = humanoid_.hinge_qvel_start();
  const double dt = m->opt.timestep;
  const std::vector<double>& kp = humanoid_.kp();
  const std::vector<double>& kd = humanoid_.kd();
  const std::vector<double>& limit = torque_limits_ != nullptr ? *torque_limits_ : humanoid_.torque_limit();
  double power = 0;
  const int substeps = humanoid_.options().substeps;
  for (int s = 0; s < substeps; ++s) {
    mj_step1(m, data);
    mj_fullM(m, dense_mass_.data(), data->qM);
    for (int r = 0; r < nv; ++r) {
      for (int c = 0; c < nv; ++c) system_(r, c) = dense_mass_[r * nv + c];
      rhs_[r] = data->qfrc_passive[r] - data->qfrc_bias[r];
    }
    for (int h = 0; h < hinges; ++h) {
      const int v = qvel0 + h;
      const double q = data->qpos[qpos0 + h], qdot = data->qvel[v];
      system_(v, v) += dt * kd[h];
      rhs_[v] += -kp[h] * (q + dt * qdot - targets[h]) - kd[h] * qdot;
    }
    solver_.compute(system_);
    acceleration_ = solver_.solve(rhs_);
    for (int h = 0; h < hinges; ++h) {
      const int v = qvel0 + h;
      const double q = data->qpos[qpos0 + h], qdot = data->qvel[v];
      const double tau = -kp[h] * (q + dt * qdot - targets[h]) - kd[h] * (qdot + dt * acceleration_[v]);
      data->qfrc_applied[v] = std::clamp(tau, -limit[h], limit[h]);
      power += std::abs(data->qfrc_applied[v] * qdot);
    }
    mj_step2(m, data);
  }
  return power / substeps;
}

}  // namespace modskill
