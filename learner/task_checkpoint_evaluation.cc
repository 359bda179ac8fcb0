#include "learner/task_checkpoint_evaluation.h"

#include <optional>

#include "absl/strings/str_cat.h"
#include "common/log.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/policy_enums.h"
#include "learner/reach_teacher.h"
#include "learner/skill_library.h"
#include "learner/trainer_config.h"

namespace modskill::learner {
namespace {

// The one-env session's spec: the task observation the head was exported for.
absl::StatusOr<v1::EnvSpec> TaskSpec(SimulationClient& client, const v1::SessionConfig& session) {
  v1::SessionConfig probe = session;
  probe.set_num_envs(1);
  auto stream = client.OpenSession(probe);
  if (!stream.ok()) return stream.status();
  v1::EnvSpec spec = (*stream)->spec();
  (void)(*stream)->Close();
  return spec;
}

}  // namespace

absl::StatusOr<TaskEvaluationReport> EvaluateTaskCheckpoint(SimulationClient& client,
                                                            const TaskCheckpointEvaluation& request) {
  auto file = ReadExportedPolicy(request.checkpoint);
  if (!file.ok()) return file.status();
  auto described = client.Describe(file->spec.part_layout);
  if (!described.ok()) return described.status();
  if (absl::Status status = CheckTaskOffered(*described, request.task, client.server()); !status.ok()) return status;
  TaskEvaluationOptions options;
  options.session.set_part_layout(file->spec.part_layout);
  options.session.set_task(request.task);
  *options.session.mutable_task_settings() = request.task_settings;
  options.session.set_action_mode(ToWire(file->spec.action.mode));
  if (file->spec.action.mode == ActionMode::kResidual) {
    options.session.set_residual_scale(static_cast<float>(file->spec.action.residual_scale));
  }
  options.session.set_termination(v1::EVALUATION);
  options.session.set_max_episode_steps(request.max_episode_steps);
  for (const std::string& clip : request.motions) options.session.add_motions(clip);
  options.episodes = request.episodes;
  options.seed = request.seed;
  options.baselines = request.baselines;
  auto task_spec = TaskSpec(client, options.session);
  if (!task_spec.ok()) return task_spec.status();
  auto imported = ImportTaskPolicy(request.checkpoint, *task_spec);
  if (!imported.ok()) return imported.status();
  if (!request.skills.empty()) {
    auto skills = SkillLibrary::Load(request.skills);
    if (!skills.ok()) return absl::Status(skills.status().code(), absl::StrCat("--skills: ", skills.status().message()));
    if (absl::Status status = skills->CheckFits(*described, *task_spec); !status.ok()) return status;
    if (absl::Status status = skills->CheckSameControllers(*imported->policy); !status.ok()) return status;
  }
  std::optional<ReachTeacher> teacher;
  if (!request.teacher.empty()) {
    if (request.task != "reach" || !imported->policy->uses_skill_prior() || !options.baselines) {
      return absl::InvalidArgumentError(
          "--task_teacher: with --eval, only for a reach policy with a skill prior and --task_baselines");
    }
    auto loaded = ReachTeacher::Load(request.teacher);
    if (!loaded.ok()) return loaded.status();
    auto mask = loaded->PartMask(imported->policy->layout(), imported->policy->config().embed_dim, request.task_parts);
    if (!mask.ok()) return mask.status();
    teacher = *std::move(loaded);
    options.teacher = &*teacher;
    options.teacher_parts = *std::move(mask);
  }
  LogLine("evaluating %s on %s, task %s, %d episodes per run", request.checkpoint, client.server(), request.task,
          options.episodes);
  return EvaluateTaskPolicy(client, *imported, request.checkpoint, options);
}

}  // namespace modskill::learner
