#include "learner/family/family_trainer.h"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "common/policy/termination.h"
#include "learner/family/family_session.h"
#include "learner/wire_torch.h"

namespace modskill::learner::family {

namespace {

absl::Status CheckConfig(const FamilyTrainerConfig& c) {
  if (c.clip.empty()) return absl::InvalidArgumentError("--family: names no clip");
  if (c.run_dir.empty()) return absl::InvalidArgumentError("--run_dir: empty");
  if (c.num_envs < 1 || c.num_envs > 4096) return absl::InvalidArgumentError("--num_envs: outside [1, 4096]");
  if (c.horizon < 2 || c.horizon > 4096) return absl::InvalidArgumentError("--horizon: outside [2, 4096]");
  if (c.epochs < 1 || c.minibatches < 1 || c.minibatches > c.num_envs * c.horizon) {
    return absl::InvalidArgumentError("--epochs/--minibatches: at least 1, at most one sample a minibatch");
  }
  if (!(c.residual_scale > 0 && c.residual_scale <= 10)) {
    return absl::InvalidArgumentError("--residual_scale: outside (0, 10]");
  }
  if (!(c.learning_rate > 0 && c.learning_rate < 1)) return absl::InvalidArgumentError("--learning_rate: outside (0, 1)");
  if (!(c.target_kl >= 0 && c.target_kl < 10)) return absl::InvalidArgumentError("--family_target_kl: outside [0, 10)");
  // 0 leaves the server's family default; any other value is checked as the server checks it.
  if (c.termination_distance != 0) {
    if (absl::Status valid = ValidateTerminationDistance(c.termination_distance); !valid.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("--family_", valid.message()));
    }
  }
  if (c.net_every < 1) return absl::InvalidArgumentError("--family_net_every: must be >= 1");
  return absl::OkStatus();
}

std::vector<bool> FreeDims(const ParamSpace& space) {
  std::vector<bool> free;
  for (int d = 0; d < space.dims(); ++d) free.push_back(!space.is_constraint(d));
  return free;
}

}  // namespace

FamilyTrainer::FamilyTrainer(FamilyTrainerConfig config) : config_(std::move(config)), rng_(config_.seed) {}
FamilyTrainer::~FamilyTrainer() = default;

absl::StatusOr<std::unique_ptr<FamilyTrainer>> FamilyTrainer::Create(FamilyTrainerConfig config) {
  if (absl::Status status = CheckConfig(config); !status.ok()) return status;
  auto space = ParamSpace::Create(config.ranges);
  if (!space.ok()) return absl::InvalidArgumentError(absl::StrCat("--param: ", space.status().message()));
  std::unique_ptr<FamilyTrainer> trainer(new FamilyTrainer(std::move(config)));
  trainer->space_ = std::make_unique<ParamSpace>(*std::move(space));
  trainer->free_dims_ = FreeDims(*trainer->space_);
  if (absl::Status status = trainer->Open(); !status.ok()) return status;
  auto curriculum = ParameterCurriculum::Create(*trainer->space_, trainer->config_.curriculum, trainer->config_.seed);
  if (!curriculum.ok()) return curriculum.status();
  trainer->curriculum_ = std::make_unique<ParameterCurriculum>(*std::move(curriculum));
  FamilyPolicyConfig policy{trainer->obs_size_, trainer->action_size_, trainer->config_.policy_hidden,
                            trainer->config_.value_hidden};
  torch::manual_seed(trainer->config_.seed);
  trainer->model_ = FamilyActorCritic(policy);
  trainer->optimizer_ = std::make_unique<torch::optim::Adam>(trainer->model_->parameters(),
                                                             torch::optim::AdamOptions(trainer->config_.learning_rate));
  trainer->learning_rate_ =
      std::make_unique<KlAdaptiveLearningRate>(trainer->config_.learning_rate, trainer->config_.target_kl);
  trainer->elites_ = std::make_unique<EliteSet>(trainer->space_->dims(), trainer->frames_, trainer->action_size_);
  trainer->net_ = ParameterizationNet(ParameterizationNetConfig{trainer->space_->dims(), trainer->action_size_});
  trainer->net_optimizer_ = std::make_unique<torch::optim::Adam>(trainer->net_->parameters(), torch::optim::AdamOptions(1e-3));
  std::filesystem::create_directories(trainer->config_.run_dir);
  if (trainer->config_.resume) {
    if (absl::Status status = trainer->LoadCheckpoint(); !status.ok()) return status;
    // The saved net was fitted to these elites' forerunners; one fit makes policy.pt's P(a) theirs.
    if (trainer->elites_->size() > 0) trainer->net_loss_ = trainer->FitNet();
  }
  // A fresh run in a used run directory starts its own coverage curve, not one after the old run's.
  auto progress = CsvLogger::Open(trainer->config_.run_dir + "/progress.csv", FamilyProgressColumns(),
                                  trainer->config_.resume ? CsvLogger::Start::kAppend : CsvLogger::Start::kFresh);
  if (!progress.ok()) return progress.status();
  trainer->progress_ = *std::move(progress);
  trainer->batch_ = trainer->curriculum_->SampleExploration(trainer->config_.curriculum.params_per_batch);
  trainer->AssignBatch();
  return trainer;
}

absl::Status FamilyTrainer::Open() {
  auto client = SimulationClient::Connect(config_.client);
  if (!client.ok()) return client.status();
  client_ = *std::move(client);
  auto motions = client_->ListMotions();
  if (!motions.ok()) return motions.status();
  for (const v1::MotionInfo& info : motions->motions()) {
    if (info.name() == config_.clip) frames_ = info.frames();
  }
  if (frames_ < 2) return absl::NotFoundError(absl::StrCat("--family: the server has no clip '", config_.clip, "'"));
  FamilySessionSettings settings;
  settings.clip = config_.clip;
  settings.ranges = config_.ranges;
  settings.num_envs = config_.num_envs;
  settings.seed = config_.seed;
  settings.residual_scale = config_.residual_scale;
  settings.termination_distance = config_.termination_distance;
  auto stream = client_->OpenSession(FamilySessionConfig(settings));
  if (!stream.ok()) return stream.status();
  stream_ = *std::move(stream);
  const v1::EnvSpec& spec = stream_->spec();
  obs_size_ = spec.obs_size();
  action_size_ = spec.action_size();
  time_warp_ = spec.time_warp_action();
  goal_start_ = spec.goal_obs().start();
  auto obs = WireToTorch(stream_->opened().initial().obs(), "SessionOpened.initial.obs", v1::FLOAT32,
                         {config_.num_envs, obs_size_});
  if (!obs.ok()) return obs.status();
  obs_ = *obs;
  template_obs_ = obs_[0].clone();
  episodes_.assign(config_.num_envs, EnvEpisode());
  return absl::OkStatus();
}

// Env i runs vector i mod batch size from its next episode on.
void FamilyTrainer::AssignBatch() {
  const int count = static_cast<int>(batch_.params.size());
  std::vector<float> rows;
  rows.reserve(static_cast<size_t>(config_.num_envs) * space_->dims());
  for (int i = 0; i < config_.num_envs; ++i) {
    episodes_[i].batch_slot = i % count;
    absl::StatusOr<std::vector<double>> a = space_->Denormalize(batch_.params[i % count]);
    for (double value : *a) rows.push_back(static_cast<float>(value));
  }
  stream_->SetFamilyParameters(rows);
  batch_episodes_ = batch_new_elites_ = 0;
}

}  // namespace modskill::learner::family
