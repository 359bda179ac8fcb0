// A compiled humanoid: the immutable mjModel plus the index tables and PD constants every env
// shares. Built once per (spec, options); envs only own their mjData.
#ifndef MODSKILL_SERVER_CORE_SIM_HUMANOID_MODEL_H_
#define MODSKILL_SERVER_CORE_SIM_HUMANOID_MODEL_H_

#include <memory>
#include <string>
#include <vector>

#include <mujoco/mujoco.h>

#include "absl/status/statusor.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/physics_options.h"

namespace modskill {

class HumanoidModel {
 public:
  static absl::StatusOr<std::shared_ptr<const HumanoidModel>> Create(const HumanoidSpec& spec,
                                                                     const PhysicsOptions& options);
  ~HumanoidModel();
  HumanoidModel(const HumanoidModel&) = delete;
  HumanoidModel& operator=(const HumanoidModel&) = delete;

  const mjModel* model() const { return model_; }
  const HumanoidSpec& spec() const { return spec_; }
  const PhysicsOptions& options() const { return options_; }
  const std::string& mjcf() const { return mjcf_; }

  int num_bodies() const { return spec_.num_bodies(); }
  int num_hinges() const { return spec_.num_hinges(); }
  // MuJoCo body id of spec body i (the world is body 0).
  int mj_body_id(int i) const { return i + 1; }
  // Offsets of the hinges inside qpos / qvel: after the free joint's 7 / 6 numbers, or at 0
  // when the root is fixed.
  int hinge_qpos_start() const { return options_.fixed_root ? 0 : 7; }
  int hinge_qvel_start() const { return options_.fixed_root ? 0 : 6; }

  // Action a in [-1, 1] maps to the PD target offset + scale * a (PHC), per hinge.
  const std::vector<double>& action_offset() const { return action_offset_; }
  const std::vector<double>& action_scale() const { return action_scale_; }
  const std::vector<double>& kp() const { return kp_; }
  const std::vector<double>& kd() const { return kd_; }
  const std::vector<double>& torque_limit() const { return torque_limit_; }

 private:
  HumanoidModel() = default;
  mjModel* model_ = nullptr;
  HumanoidSpec spec_;
  PhysicsOptions options_;
  std::string mjcf_;
  std::vector<double> action_offset_, action_scale_, kp_, kd_, torque_limit_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_HUMANOID_MODEL_H_
