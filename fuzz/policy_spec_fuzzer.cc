// libFuzzer target: a policy checkpoint's metadata, the JSON its archive carries as
// modskill/env_spec.json (PolicySpec::FromJson, common/policy/policy_spec.cc), then what
// Rollout does with a spec that parses: look up its layout and check it against that layout's
// env spec. The zip container around the JSON is torch's reader (torch::jit::load), not ours,
// and stays out of the torch-free fuzz build.
//
// A spec that parses must keep the bounds FromJson promises and survive ToJson -> FromJson.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/policy/family_elites.h"
#include "common/policy/policy_spec.h"
#include "common/servo_settings.h"
#include "fuzz/fuzz_service.h"
#include "server/core/env/policy_fit.h"

namespace modskill::fuzz {
namespace {

void FuzzPolicySpec(const uint8_t* data, size_t size) {
  auto spec = PolicySpec::FromJson(absl::string_view(reinterpret_cast<const char*>(data), size));
  if (!spec.ok()) {
    Check(spec.status().code() == absl::StatusCode::kInvalidArgument, "a bad spec is INVALID_ARGUMENT");
    return;
  }
  Check(spec->obs_size >= 1 && spec->obs_size <= kMaxPolicyVectorSize, "obs_size in bounds");
  Check(spec->action_size >= 1 && spec->action_size <= kMaxPolicyVectorSize, "action_size in bounds");
  Check(spec->joint_names.size() <= static_cast<size_t>(kMaxPolicyVectorSize), "joint_names bounded");
  Check(spec->control_dt > 0 && spec->control_dt < 10, "control_dt in (0, 10)");
  Check(spec->action.Validate().ok(), "valid action mapping");
  Check(!spec->physics.recorded() || (spec->physics.physics_dt <= 1 &&
                                      ValidatePdGainScale(spec->physics.pd_gain_scale, "pd_gain_scale").ok() &&
                                      IsPdModeName(spec->physics.pd_mode)),
        "recorded physics in bounds");

  auto again = PolicySpec::FromJson(spec->ToJson());
  Check(again.ok(), "ToJson output parses");
  Check(again->part_layout == spec->part_layout && again->obs_size == spec->obs_size &&
            again->action_size == spec->action_size && again->joint_names == spec->joint_names &&
            again->control_dt == spec->control_dt && again->action.mode == spec->action.mode &&
            again->action.residual_scale == spec->action.residual_scale && again->task == spec->task &&
            again->controller_input == spec->controller_input && again->family_clip == spec->family_clip &&
            again->family_frames == spec->family_frames && again->family.size() == spec->family.size() &&
            again->physics.physics_dt == spec->physics.physics_dt && again->physics.pd_mode == spec->physics.pd_mode &&
            again->physics.pd_gain_scale == spec->physics.pd_gain_scale &&
            again->physics.damp_to_reference_rate == spec->physics.damp_to_reference_rate,
        "ToJson -> FromJson is the identity");
  for (size_t k = 0; k < spec->family.size(); ++k) {
    Check(again->family[k].name == spec->family[k].name && again->family[k].lo == spec->family[k].lo &&
              again->family[k].hi == spec->family[k].hi && ValidateParamRange(spec->family[k]).ok(),
          "a family's ranges are valid and survive ToJson -> FromJson");
  }

  const ServiceFixture& fixture = Fixture();
  auto env_spec = fixture.env_specs.find(spec->part_layout);
  if (env_spec == fixture.env_specs.end()) return;  // Rollout: FAILED_PRECONDITION, unknown layout
  const absl::Status compatible = CheckPolicyFitsEnv(*spec, env_spec->second);
  Check(compatible.ok() || compatible.code() == absl::StatusCode::kFailedPrecondition,
        "an incompatible spec is FAILED_PRECONDITION");
}

// A family policy's elite file (modskill/family_elites.json): INVALID_ARGUMENT or elites of the
// asked-for size with finite values.
void FuzzFamilyElites(const uint8_t* data, size_t size) {
  const absl::string_view text(reinterpret_cast<const char*>(data), size);
  for (int dims : {1, 2}) {
    auto elites = FamilyElitesFromJson(text, dims);
    if (!elites.ok()) {
      Check(elites.status().code() == absl::StatusCode::kInvalidArgument, "bad elites are INVALID_ARGUMENT");
      continue;
    }
    for (const FamilyEliteRecord& elite : *elites) {
      Check(static_cast<int>(elite.params.size()) == dims && std::isfinite(elite.fitness), "elites as promised");
    }
  }
}

}  // namespace
}  // namespace modskill::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  modskill::fuzz::Fixture();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  modskill::fuzz::FuzzPolicySpec(data, size);
  modskill::fuzz::FuzzFamilyElites(data, size);
  return 0;
}
