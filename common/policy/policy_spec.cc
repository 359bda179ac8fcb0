#include "common/policy/policy_spec.h"

#include <cstdint>
#include <utility>

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "common/shown_value.h"

namespace modskill {

std::string PolicySpec::ToJson() const {
  nlohmann::json json;
  json["part_layout"] = part_layout;
  json["obs_size"] = obs_size;
  json["action_size"] = action_size;
  json["joint_names"] = joint_names;
  json["control_dt"] = control_dt;
  if (physics.recorded()) json["physics"] = nlohmann::json::parse(physics.ToJson());
  json["action_mode"] = ActionModeName(action.mode);
  json["residual_scale"] = action.residual_scale;
  json["task"] = task;
  json["controller_input"] = controller_input;
  if (reference_frames != 1) json["reference_frames"] = reference_frames;
  if (is_family()) {
    json["family_clip"] = family_clip;
    json["family_frames"] = family_frames;
    for (const ParamRange& range : family) json["family"].push_back({{"name", range.name}, {"lo", range.lo}, {"hi", range.hi}});
  }
  return json.dump(1);
}

namespace {

// Task names are identifiers the server lists (EnvSpec.tasks); anything else in a file is damage.
bool IsTaskName(absl::string_view name) {
  if (name.empty() || name.size() > 32) return false;
  for (char c : name) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  }
  return true;
}

constexpr int kMaxFamilyFrames = 1000000;

// The family fields, when present (a family policy's): every range valid, no name twice.
absl::Status ReadFamily(const nlohmann::json& json, PolicySpec* spec) {
  if (!json.contains("family")) return absl::OkStatus();
  const auto bad = [](absl::string_view field, absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", field, ": ", why));
  };
  const nlohmann::json& ranges = json.at("family");
  if (!ranges.is_array() || ranges.empty() || ranges.size() > 64) return bad("family", "not a list of 1 to 64 ranges");
  for (size_t k = 0; k < ranges.size(); ++k) {
    ParamRange range{ranges[k].at("name").get<std::string>(), ranges[k].at("lo").get<double>(),
                     ranges[k].at("hi").get<double>()};
    if (absl::Status status = ValidateParamRange(range); !status.ok()) {
      return bad(absl::StrCat("family[", k, "]"), status.message());
    }
    for (const ParamRange& seen : spec->family) {
      if (seen.name == range.name) return bad(absl::StrCat("family[", k, "]"), absl::StrCat(range.name, " given twice"));
    }
    spec->family.push_back(std::move(range));
  }
  spec->family_clip = json.at("family_clip").get<std::string>();
  if (spec->family_clip.empty() || spec->family_clip.size() > kMaxShownValueBytes) {
    return bad("family_clip", "not a clip name");
  }
  const nlohmann::json& frames = json.at("family_frames");
  if (!frames.is_number_integer() || frames.get<int64_t>() < 2 || frames.get<int64_t>() > kMaxFamilyFrames) {
    return bad("family_frames", absl::StrCat(ShownValue(frames.dump()), " is not an integer in [2, ", kMaxFamilyFrames, "]"));
  }
  spec->family_frames = static_cast<int>(frames.get<int64_t>());
  return absl::OkStatus();
}

// The upcoming reference frames a tracker observes (1 when the file predates the field).
absl::Status ReadReferenceFrames(const nlohmann::json& json, PolicySpec* spec) {
  if (!json.contains("reference_frames")) return absl::OkStatus();
  if (!json.at("reference_frames").is_number_integer()) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": reference_frames: ",
                                                   ShownValue(json.at("reference_frames").dump()),
                                                   " is not an integer"));
  }
  const int64_t frames = json.at("reference_frames").get<int64_t>();
  if (frames < 1 || frames > kMaxReferenceFrames) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": reference_frames: ", frames,
                                                   " is not in [1, ", kMaxReferenceFrames, "]"));
  }
  spec->reference_frames = static_cast<int>(frames);
  return absl::OkStatus();
}

// The physics the policy was trained under (not recorded when the file predates the field).
absl::Status ReadPhysics(const nlohmann::json& json, PolicySpec* spec) {
  if (!json.contains("physics")) return absl::OkStatus();
  auto physics = PhysicsSettings::FromJson(json.at("physics").dump(), kCheckpointSpecFile);
  if (!physics.ok()) return physics.status();
  spec->physics = *std::move(physics);
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<PolicySpec> PolicySpec::FromJson(absl::string_view text) {
  nlohmann::json json = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded() || !json.is_object()) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": not a JSON object"));
  }
  PolicySpec spec;
  // Sizes are read as they are written, not cast: 2^40 must not become 0.
  auto size = [&](const char* key) -> absl::StatusOr<int> {
    const nlohmann::json& value = json.at(key);
    if (!value.is_number_integer() || value.get<int64_t>() < 1 || value.get<int64_t>() > kMaxPolicyVectorSize) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", key, ": ", value.dump().substr(0, 32),
                                                     " is not an integer in [1, ", kMaxPolicyVectorSize, "]"));
    }
    return static_cast<int>(value.get<int64_t>());
  };
  try {
    spec.part_layout = json.at("part_layout").get<std::string>();
    if (spec.part_layout.size() > kMaxShownValueBytes) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": part_layout: ", spec.part_layout.size(),
                                                     " characters, longer than any layout name"));
    }
    auto obs_size = size("obs_size");
    if (!obs_size.ok()) return obs_size.status();
    spec.obs_size = *obs_size;
    auto action_size = size("action_size");
    if (!action_size.ok()) return action_size.status();
    spec.action_size = *action_size;
    spec.joint_names = json.at("joint_names").get<std::vector<std::string>>();
    if (static_cast<int64_t>(spec.joint_names.size()) > kMaxPolicyVectorSize) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": joint_names: too many"));
    }
    spec.control_dt = json.at("control_dt").get<double>();
    if (!(spec.control_dt > 0 && spec.control_dt < 10)) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": control_dt: ", spec.control_dt,
                                                     " is not in (0, 10) s"));
    }
    if (absl::Status status = ReadPhysics(json, &spec); !status.ok()) return status;
    if (json.contains("action_mode")) {
      auto mode = ParseActionMode(json.at("action_mode").get<std::string>());
      if (!mode.ok()) return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": action_mode: ", mode.status().message()));
      spec.action.mode = *mode;
    }
    if (json.contains("residual_scale")) spec.action.residual_scale = json.at("residual_scale").get<double>();
    for (auto [key, field] : {std::pair<const char*, std::string*>{"task", &spec.task},
                              {"controller_input", &spec.controller_input}}) {
      if (!json.contains(key)) continue;
      if (!json.at(key).is_string()) {
        return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", key, ": ",
                                                       ShownValue(json.at(key).dump()), " is not a string"));
      }
      *field = json.at(key).get<std::string>();
    }
    if (!IsTaskName(spec.task)) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": task: ", ShownValue(spec.task),
                                                     " is not a task name ([a-z0-9_], 1 to 32 characters)"));
    }
    if (spec.controller_input != kPartObsControllerInput && spec.controller_input != kProprioceptionControllerInput) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": controller_input: ",
                                                     ShownValue(spec.controller_input), " is not ",
                                                     kPartObsControllerInput, " or ", kProprioceptionControllerInput));
    }
    if (absl::Status status = ReadReferenceFrames(json, &spec); !status.ok()) return status;
    if (absl::Status status = ReadFamily(json, &spec); !status.ok()) return status;
    if (spec.reference_frames > 1 && (spec.task != kTrackingTask || spec.is_family())) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": reference_frames: ",
                                                     spec.reference_frames, " for ",
                                                     spec.is_family() ? "a family" : "task " + spec.task,
                                                     "; only a tracker observes more than one"));
    }
  } catch (const nlohmann::json::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", ShownValue(e.what())));
  }
  if (absl::Status status = spec.action.Validate(); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", status.message()));
  }
  return spec;
}

}  // namespace modskill
