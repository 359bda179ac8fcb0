#include "server/core/sim/humanoid_model.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "server/core/sim/mjcf_builder.h"
#include "server/core/sim/mujoco_warnings.h"

namespace modskill {

absl::StatusOr<std::shared_ptr<const HumanoidModel>> HumanoidModel::Create(const HumanoidSpec& spec,
                                                                           const PhysicsOptions& options) {
  RouteMujocoWarningsToLog();  // before MuJoCo can write MUJOCO_LOG.TXT
  if (!(options.control_hz > 0 && options.control_hz <= 1000)) {
    return absl::InvalidArgumentError(absl::StrCat("control_hz: ", options.control_hz, " outside (0, 1000]"));
  }
  if (absl::Status status = ValidateSubsteps(options.substeps, "substeps"); !status.ok()) return status;
  if (absl::Status status = ValidatePdGainScale(options.pd_gain_scale, "pd_gain_scale"); !status.ok()) return status;
  std::shared_ptr<HumanoidModel> humanoid(new HumanoidModel());
  humanoid->spec_ = spec;
  humanoid->options_ = options;
  humanoid->mjcf_ = BuildHumanoidMjcf(spec, options);

  // Compile from memory through MuJoCo's virtual file system: nothing touches the disk.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const char* kFileName = "modskill_humanoid.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), kFileName, static_cast<int>(humanoid->mjcf_.size())) != 0) {
    return absl::InternalError("MuJoCo VFS: cannot allocate the generated MJCF");
  }
  const int file_index = mj_findFileVFS(vfs.get(), kFileName);
  std::memcpy(vfs->filedata[file_index], humanoid->mjcf_.data(), humanoid->mjcf_.size());
  char error[1000] = "";
  humanoid->model_ = mj_loadXML(kFileName, vfs.get(), error, sizeof(error));
  mj_deleteVFS(vfs.get());
  if (humanoid->model_ == nullptr) {
    return absl::InvalidArgumentError(absl::StrCat("generated MJCF does not compile: ", error));
  }

  for (int i = 1; i < spec.num_bodies(); ++i) {
    const BodySpec& body = spec.body(i);
    for (int a = 0; a < 3; ++a) {
      const double low = body.range_low[a], high = body.range_high[a];
      humanoid->action_offset_.push_back(0.5 * (low + high));
      // PHC: scale reaches a bit past the joint limits, capped at pi.
      humanoid->action_scale_.push_back(std::min(1.2 * 0.5 * (high - low), M_PI));
      humanoid->kp_.push_back(options.pd_gain_scale * body.kp);
      humanoid->kd_.push_back(options.pd_gain_scale * body.kd);
      humanoid->torque_limit_.push_back(body.torque_limit);
    }
  }
  return std::shared_ptr<const HumanoidModel>(std::move(humanoid));
}

HumanoidModel::~HumanoidModel() {
  if (model_ != nullptr) mj_deleteModel(model_);
}

}  // namespace modskill
