#include "client/cpp/step_result_check.h"

#include <cstdint>
#include <string>

#include "absl/strings/str_cat.h"
#include "common/wire/step_result_fields.h"
#include "common/wire/tensor_codec.h"

namespace modskill {
namespace {

// What the session's spec says of each field's width; amp_obs may come as the whole history or
// the newest frame only, so any whole number of frames is accepted.
StepResultWidths WidthsOf(const v1::EnvSpec& spec) {
  StepResultWidths widths;
  widths.obs = spec.obs_size();
  widths.amp_obs = kAnySize;
  widths.reward_terms = spec.reward_terms_size();
  widths.parts = spec.parts_size();
  widths.family_params = spec.family_size();
  return widths;
}

absl::Status CheckField(const v1::Tensor& tensor, const char* field, v1::DType dtype, int num_envs, int64_t width) {
  const std::string name = absl::StrCat("StepResult.", field);
  if (width == StepResultWidths::kVector) return AsDataLoss(CheckTensor(tensor, name, dtype, {num_envs}));
  return AsDataLoss(CheckTensor(tensor, name, dtype, {num_envs, width}));
}

absl::Status CheckAmpFrames(const v1::StepResult& result, const v1::EnvSpec& spec) {
  const int64_t per_frame = spec.amp_obs_per_frame();
  if (!result.has_amp_obs() || per_frame <= 0 || result.amp_obs().shape(1) % per_frame == 0) return absl::OkStatus();
  return absl::DataLossError(absl::StrCat("StepResult.amp_obs: width ", result.amp_obs().shape(1),
                                          " is not a whole number of ", per_frame, "-feature frames"));
}

}  // namespace

absl::Status CheckStepResult(const v1::StepResult& result, int num_envs, const v1::EnvSpec& spec) {
  const StepResultWidths widths = WidthsOf(spec);
  // A field that may be absent is checked when it is there (an empty optional one counts as absent);
  // a family session must send the family's fields, other sessions' are not looked at.
#define MODSKILL_CHECK_FIELD(name, type, dtype, width, initial, presence)                                  \
  {                                                                                                        \
    constexpr StepResultPresence kPresence = StepResultPresence::presence;                                 \
    const bool present = kPresence == StepResultPresence::kAlways ||                                       \
                         (kPresence == StepResultPresence::kFamily                                         \
                              ? widths.family_params > 0                                                   \
                              : result.has_##name() && (kPresence != StepResultPresence::kOptional ||      \
                                                        result.name().shape_size() > 0));                  \
    if (present) {                                                                                         \
      if (absl::Status status = CheckField(result.name(), #name, v1::dtype, num_envs, widths.width);       \
          !status.ok()) {                                                                                  \
        return status;                                                                                     \
      }                                                                                                    \
    }                                                                                                      \
  }
  MODSKILL_STEP_RESULT_FIELDS(MODSKILL_CHECK_FIELD)
#undef MODSKILL_CHECK_FIELD
  return CheckAmpFrames(result, spec);
}

}  // namespace modskill
