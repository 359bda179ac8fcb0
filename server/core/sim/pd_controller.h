// Turns PD targets into joint torques for one control step (all of its physics substeps).
#ifndef MODSKILL_SERVER_CORE_SIM_PD_CONTROLLER_H_
#define MODSKILL_SERVER_CORE_SIM_PD_CONTROLLER_H_

#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <mujoco/mujoco.h>

#include "server/core/sim/humanoid_model.h"

namespace modskill {

class PdController {
 public:
  // Preallocates everything the step needs.
  explicit PdController(const HumanoidModel& humanoid);

  // Holds `targets` (one per hinge, MuJoCo order, radians) for options.substeps physics steps.
  // Returns the joint power sum |tau * qdot| averaged over the substeps (W).
  double Step(const double* targets, mjData* data);
  // Steps `model` from now on instead of the humanoid's own: a copy with the same sizes whose
  // physics (gravity, masses, an obstacle) one env changes (family_episode.h).
  void UseModel(const mjModel* model) { model_ = model; }
  // Stable PD clamps each hinge's torque to `limits` (one per hinge, N*m; it must outlive the
  // controller) instead of the humanoid's. Position servos take theirs from the model's
  // actuator_forcerange, which a model given to UseModel carries.
  void UseTorqueLimits(const std::vector<double>* limits) { torque_limits_ = limits; }

 private:
  double StepPositionImplicit(const double* targets, mjData* data);
  double StepStablePd(const double* targets, mjData* data);

  const HumanoidModel& humanoid_;
  const mjModel* model_;
  const std::vector<double>* torque_limits_ = nullptr;
  std::vector<mjtNum> dense_mass_;
  Eigen::MatrixXd system_;
  Eigen::VectorXd rhs_, acceleration_;
  Eigen::LLT<Eigen::MatrixXd> solver_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_PD_CONTROLLER_H_
