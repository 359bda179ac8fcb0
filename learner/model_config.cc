#include "learner/model_config.h"

#include "absl/strings/str_cat.h"

namespace modskill::learner {

absl::StatusOr<ModelConfig> ModelConfig::Preset(absl::string_view name) {
  ModelConfig config;
  config.preset = std::string(name);
  if (name == "paper") {
    config.attention_hidden = {256};
    config.embed_dim = 64;
    config.controller_hidden = {2048, 1536, 1024, 512};
    config.critic_hidden = {2048, 1536, 1024, 512};
    config.discriminator_hidden = {1024, 512};
    config.task_hidden = {2048, 1024, 512};
  } else if (name == "small") {
    config.attention_hidden = {64};
    config.embed_dim = 32;
    config.controller_hidden = {256, 128};
    config.critic_hidden = {256, 128};
    config.discriminator_hidden = {256, 128};
    config.task_hidden = {256, 128};
    // The newest 2 of 10 AMP frames: the update 0.97-1.00 -> 0.68-0.79 s per 8,192 steps; at
    // 1 M steps the walk learns alike and cmu_02_01 evaluates closer (README, "Learning").
    config.amp_frames = 2;
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("model preset '", name, "' not found (known presets: paper, small)"));
  }
  return config;
}

ModelConfig ModelConfig::WithPolicyShapeOf(const ModelConfig& policy) const {
  ModelConfig config = *this;
  config.attention_hidden = policy.attention_hidden;
  config.embed_dim = policy.embed_dim;
  config.controller_hidden = policy.controller_hidden;
  config.controller_input = policy.controller_input;
  config.log_std = policy.log_std;
  config.whole_body = policy.whole_body;
  config.attention = policy.attention;
  return config;
}

namespace {

// Checks that the slices [start, start + size) of the parts tile [0, total) in part order.
absl::Status CheckTiling(const NetworkLayout& layout, absl::string_view what, int64_t total,
                         int64_t PartSlices::*start, int64_t PartSlices::*size) {
  int64_t expected = 0;
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    const PartSlices& part = layout.parts[p];
    if (part.*size <= 0) {
      return absl::InvalidArgumentError(
          absl::StrCat("network layout: part ", p, " '", part.name, "': ", what, " size is ", part.*size,
                       ", must be > 0"));
    }
    if (part.*start != expected) {
      return absl::InvalidArgumentError(absl::StrCat(
          "network layout: part ", p, " '", part.name, "': ", what, " slice [", part.*start, ", ",
          part.*start + part.*size, ") ", part.*start < expected ? "overlaps the previous part" : "leaves a gap",
          " (expected it to start at ", expected, "; ", what, " slices must tile [0, ", total, ") in part order)"));
    }
    expected += part.*size;
  }
  if (expected != total) {
    const PartSlices& last = layout.parts.back();
    return absl::InvalidArgumentError(absl::StrCat("network layout: part ", layout.parts.size() - 1, " '", last.name,
                                                   "': ", what, " slices end at ", expected, ", but ", what,
                                                   layout.has_goal() && what == "obs" ? " ends (where the goal starts) at "
                                                                                      : "_size is ",
                                                   total));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status NetworkLayout::Validate() const {
  if (obs_size <= 0) return absl::InvalidArgumentError(absl::StrCat("network layout: obs_size is ", obs_size));
  if (action_size <= 0) {
    return absl::InvalidArgumentError(absl::StrCat("network layout: action_size is ", action_size));
  }
  if (amp_obs_size < 0) {
    return absl::InvalidArgumentError(absl::StrCat("network layout: amp_obs_size is ", amp_obs_size));
  }
  if (parts.empty()) return absl::InvalidArgumentError("network layout: no parts");
  if (goal_size < 0 || (has_goal() && goal_start + goal_size != obs_size)) {
    return absl::InvalidArgumentError(absl::StrCat("network layout: task ", task, ": goal [", goal_start, ", ",
                                                   goal_start + goal_size, ") does not end the observation (obs_size ",
                                                   obs_size, ")"));
  }
  if (absl::Status s = CheckTiling(*this, "obs", parts_obs_end(), &PartSlices::obs_start, &PartSlices::obs_size);
      !s.ok()) {
    return s;
  }
  for (const PartSlices& part : parts) {
    for (const auto& [start, size] : part.self_obs) {
      if (size <= 0 || start < part.obs_start || start + size > part.obs_start + part.obs_size) {
        return absl::InvalidArgumentError(absl::StrCat("network layout: part '", part.name, "' self_obs [", start, ", ",
                                                       start + size, ") is not inside its obs slice"));
      }
    }
  }
  return CheckTiling(*this, "action", action_size, &PartSlices::action_start, &PartSlices::action_size);
}

absl::Status ReadAmpFrames(int64_t frames, NetworkLayout* layout) {
  if (frames < 0 || frames > layout->amp_history) {
    return absl::InvalidArgumentError(absl::StrCat("--amp_frames: ", frames, " is not in [0, ", layout->amp_history,
                                                   "] (the server's AMP history; 0: all of it)"));
  }
  layout->amp_obs_size = (frames == 0 ? layout->amp_history : frames) * layout->amp_obs_per_frame;
  return absl::OkStatus();
}

absl::StatusOr<ModelConfig::ControllerInput> ParseControllerInput(absl::string_view name) {
  if (name == "part_obs") return ModelConfig::ControllerInput::kPartObservation;
  if (name == "proprioception") return ModelConfig::ControllerInput::kProprioception;
  return absl::InvalidArgumentError(
      absl::StrCat("--controller_input: '", name, "' is not part_obs or proprioception"));
}

const char* ControllerInputName(ModelConfig::ControllerInput input) {
  return input == ModelConfig::ControllerInput::kProprioception ? "proprioception" : "part_obs";
}

int64_t PartSlices::self_obs_size() const {
  int64_t size = 0;
  for (const auto& [start, length] : self_obs) size += length;
  return size;
}

NetworkLayout LayoutFromWireSpec(const v1::EnvSpec& spec) {
  NetworkLayout layout;
  layout.obs_size = spec.obs_size();
  layout.action_size = spec.action_size();
  layout.amp_history = spec.amp_history();
  layout.amp_obs_per_frame = spec.amp_obs_per_frame();
  layout.amp_obs_size = layout.wire_amp_obs_size();
  if (!spec.task().empty()) layout.task = spec.task();
  layout.goal_start = spec.goal_obs().start();
  layout.goal_size = spec.goal_obs().size();
  for (const v1::BodyPart& part : spec.parts()) {
    PartSlices slices;
    slices.name = part.name();
    slices.obs_start = part.obs().start();
    slices.obs_size = part.obs().size();
    slices.action_start = part.action().start();
    slices.action_size = part.action().size();
    for (const v1::Slice& self : part.self_obs()) slices.self_obs.emplace_back(self.start(), self.size());
    layout.parts.push_back(slices);
  }
  return layout;
}

}  // namespace modskill::learner
