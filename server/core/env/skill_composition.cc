#include "server/core/env/skill_composition.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {
namespace {

// A PolicyFunction over a SkillPolicy that keeps the z of its latest call ([n, P, E], allocated
// once) and lets `compose` change it between skills and act_with_z (step: calls so far).
class SkillStepper {
 public:
  using Compose = std::function<void(int step, float* z)>;
  SkillStepper(const SkillPolicy& policy, int num_envs, Compose compose = nullptr)
      : policy_(policy),
        compose_(std::move(compose)),
        z_(static_cast<size_t>(num_envs) * policy.num_parts * policy.embed_dim) {}

  absl::Status operator()(const float* obs, int n, float* actions) {
    if (absl::Status status = policy_.skills(obs, n, z_.data()); !status.ok()) return status;
    if (compose_) compose_(step_, z_.data());
    ++step_;
    return policy_.act_with_z(obs, z_.data(), n, actions);
  }

  FrameSkills frame_skills() const { return {z_.data(), int64_t{policy_.num_parts} * policy_.embed_dim}; }

 private:
  const SkillPolicy& policy_;
  Compose compose_;
  std::vector<float> z_;
  int step_ = 0;
};

absl::Status CheckPolicy(const SkillPolicy& policy, const PartLayout& layout) {
  if (!policy.skills || !policy.act_with_z || policy.embed_dim < 1) {
    return absl::FailedPreconditionError("checkpoint: no skills() and act_with_z() to compose with");
  }
  if (policy.num_parts != static_cast<int>(layout.parts.size())) {
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: skills() gives ", policy.num_parts,
                                                   " parts, the layout ", layout.name, " has ", layout.parts.size()));
  }
  return absl::OkStatus();
}

absl::Status CheckComposition(const SkillComposition& composition, const PartLayout& layout,
                              const MotionLibrary& motions) {
  for (auto [clip, field] : {std::pair{composition.base_clip, "composition.base_clip"},
                             std::pair{composition.source_clip, "composition.source_clip"}}) {
    if (clip < 0 || clip >= motions.size()) return absl::NotFoundError(absl::StrCat(field, ": no clip with index ", clip));
  }
  if (composition.parts.empty()) return absl::InvalidArgumentError("composition.parts: name at least one part");
  for (size_t i = 0; i < composition.parts.size(); ++i) {
    const int part = composition.parts[i];
    if (part < 0 || part >= static_cast<int>(layout.parts.size())) {
      return absl::InvalidArgumentError(absl::StrCat("composition.parts[", i, "]: no part ", part, " in layout ",
                                                     layout.name));
    }
    if (std::count(composition.parts.begin(), composition.parts.begin() + i, part) > 0) {
      return absl::InvalidArgumentError(absl::StrCat("composition.parts[", i, "]: ", layout.parts[part].name,
                                                     " is named twice"));
    }
  }
  return absl::OkStatus();
}

// The source clip's z, one row of P * E floats per step it acted on.
struct SourceSkills {
  std::vector<float> z;
  int steps = 0;
  bool terminated = false;
};

absl::StatusOr<SourceSkills> RecordSource(std::shared_ptr<const HumanoidModel> humanoid, const PartLayout& layout,
                                          std::shared_ptr<const MotionLibrary> motions, const SkillPolicy& policy,
                                          int clip, const RolloutOptions& options) {
  const size_t row = static_cast<size_t>(policy.num_parts) * policy.embed_dim;
  SourceSkills source;
  source.z.reserve(row * static_cast<size_t>(std::max(1, motions->clip(clip).num_frames)));
  auto metrics = RunSkillRollout(humanoid, layout, motions, {clip}, policy, options,
                                 [&](const RolloutFrameView& view) {
                                   if (view.skill_z != nullptr) source.z.insert(source.z.end(), view.skill_z, view.skill_z + row);
                                 });
  if (!metrics.ok()) return metrics.status();
  source.steps = static_cast<int>(source.z.size() / row);
  source.terminated = !metrics->front().success;
  return source;
}

// Writes the composed z of the chosen parts into z (one env: [P, E]).
void ComposeParts(const SkillComposition& composition, const SourceSkills& source, int embed_dim, double alpha,
                  int step, float* z) {
  const float* from = source.z.data() + static_cast<size_t>(std::min(step, source.steps - 1)) *
                                            (source.z.size() / std::max(1, source.steps));
  for (int part : composition.parts) {
    float* mine = z + static_cast<size_t>(part) * embed_dim;
    const float* theirs = from + static_cast<size_t>(part) * embed_dim;
    // alpha 1 is the source's z exactly.
    if (composition.mode == CompositionMode::kSwap || alpha >= 1.0) {
      std::copy(theirs, theirs + embed_dim, mine);
      continue;
    }
    // alpha 0 keeps the base's z, and so does a source z equal to it: renormalizing a unit
    // vector could move it by an ulp, and the rollout would drift from the plain one.
    if (alpha <= 0.0 || std::equal(theirs, theirs + embed_dim, mine)) continue;
    double norm = 0;
    for (int e = 0; e < embed_dim; ++e) {
      mine[e] = static_cast<float>((1.0 - alpha) * mine[e] + alpha * theirs[e]);
      norm += double{mine[e]} * mine[e];
    }
    // As the policy's own normalization: z / max(||z||, 1e-6).
    const double scale = 1.0 / std::max(std::sqrt(norm), 1e-6);
    for (int e = 0; e < embed_dim; ++e) mine[e] = static_cast<float>(mine[e] * scale);
  }
}

}  // namespace

double InterpolationAlpha(int step, int possible_steps) {
  if (possible_steps <= 1) return 1.0;
  return std::clamp(static_cast<double>(step) / (possible_steps - 1), 0.0, 1.0);
}

absl::StatusOr<std::vector<ClipRolloutMetrics>> RunSkillRollout(std::shared_ptr<const HumanoidModel> humanoid,
                                                                const PartLayout& layout,
                                                                std::shared_ptr<const MotionLibrary> motions,
                                                                const std::vector<int>& clip_ids,
                                                                const SkillPolicy& policy,
                                                                const RolloutOptions& options,
                                                                const RolloutFrameCallback& on_frame) {
  if (absl::Status status = CheckPolicy(policy, layout); !status.ok()) return status;
  SkillStepper stepper(policy, static_cast<int>(clip_ids.size()));
  return RunRollout(
      humanoid, layout, motions, clip_ids,
      [&stepper](const float* obs, int n, float* actions) { return stepper(obs, n, actions); }, options, on_frame,
      stepper.frame_skills());
}

absl::StatusOr<ComposedRolloutResult> RunComposedRollout(std::shared_ptr<const HumanoidModel> humanoid,
                                                         const PartLayout& layout,
                                                         std::shared_ptr<const MotionLibrary> motions,
                                                         const SkillPolicy& policy,
                                                         const SkillComposition& composition,
                                                         const RolloutOptions& options,
                                                         const RolloutFrameCallback& on_frame) {
  if (absl::Status status = CheckPolicy(policy, layout); !status.ok()) return status;
  if (absl::Status status = CheckComposition(composition, layout, *motions); !status.ok()) return status;
  auto source = RecordSource(humanoid, layout, motions, policy, composition.source_clip, options);
  if (!source.ok()) return source.status();
  if (source->steps < 1) return absl::InternalError("composition.source_clip: the source rollout took no step");
  // The base rollout's possible steps set alpha's pace: the clip's, or the step limit.
  int possible = motions->clip(composition.base_clip).num_frames - 1;
  if (options.max_steps_per_clip > 0) possible = std::min(possible, options.max_steps_per_clip);
  ComposedRolloutResult result;
  result.source_steps = source->steps;
  result.source_terminated = source->terminated;
  SkillStepper stepper(policy, 1, [&](int step, float* z) {
    if (step >= source->steps) ++result.held_steps;
    ComposeParts(composition, *source, policy.embed_dim, InterpolationAlpha(step, possible), step, z);
  });
  auto metrics = RunRollout(
      humanoid, layout, motions, {composition.base_clip},
      [&stepper](const float* obs, int n, float* actions) { return stepper(obs, n, actions); }, options, on_frame,
      stepper.frame_skills());
  if (!metrics.ok()) return metrics.status();
  result.metrics = std::move(metrics->front());
  return result;
}

}  // namespace modskill
