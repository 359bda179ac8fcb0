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

 private:
  double StepPositionImplicit(const double* targets, mjData* data);
  double StepStablePd(const double* targets, mjData* data);

  const HumanoidModel& humanoid_;
  const mjModel* model_;
  std::vector<mjtNum> dense_mass_;
  Eigen::MatrixXd system_;
  Eigen::VectorXd rhs_, acceleration_;
  Eigen::LLT<Eigen::MatrixXd> solver_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_PD_CONTROLLER_H_
