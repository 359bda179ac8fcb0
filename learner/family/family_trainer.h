// Trains a motor-skill family from one clip (Lee et al. 2021; DESIGN.md section 4; issue 14)
// against a server's family session (SessionConfig.family):
//   1. the curriculum (parameter_curriculum.h) picks batches of parameter vectors, which the
//      trainer hands to the envs (SimulateRequest.family_params) for their next episodes;
//   2. the policy (family_policy.h) acts: hinge displacements and the time warp;
//   3. PPO with variable time-step GAE (variable_step_gae.h) updates policy and critic, the
//      server's spike rewards kept apart from the continuous ones;
//   4. each episode that reaches the clip's end is offered to the elite set with its fitness F
//      (computed by the server) and its trajectory {(d_t, tau_t)} resampled to the clip's frames;
//   5. every few iterations the parameterization network P(a) is fitted to the elites.
// The clip's end is the motion's end: an episode that reaches it is not bootstrapped.
// run_dir gets progress.csv (one row per iteration: the coverage curve), checkpoint.pt (written
// atomically; --resume continues from it), parameterization.pt and policy.pt (family_export.h:
// the policy, P(a) and the elites in one TorchScript file for Rollout, QueryFamily and the viewer).
#ifndef MODSKILL_LEARNER_FAMILY_FAMILY_TRAINER_H_
#define MODSKILL_LEARNER_FAMILY_FAMILY_TRAINER_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <torch/torch.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/cpp/simulation_client.h"
#include "common/policy/family_parameters.h"
#include "learner/family/elite_set.h"
#include "learner/family/family_coverage.h"
#include "learner/family/family_policy.h"
#include "learner/family/parameter_curriculum.h"
#include "learner/family/parameterization_net.h"
#include "learner/kl_adaptive_learning_rate.h"
#include "learner/tensorboard_writer.h"

namespace modskill::learner::family {

struct FamilyTrainerConfig {
  ClientOptions client;
  std::string clip;                 // the one clip the family grows from
  std::vector<ParamRange> ranges;   // --param
  std::string run_dir;
  bool resume = false;
  int num_envs = 32;
  int horizon = 64;                 // steps per env per iteration
  int epochs = 4;
  int minibatches = 4;
  double learning_rate = 3e-4;      // the first; then steered by target_kl
  double target_kl = 0.01;          // KlAdaptiveLearningRate's target; 0 keeps learning_rate fixed
  double gamma = 0.95, lambda = 0.95;  // DESIGN.md
  double clip_ratio = 0.2;
  double residual_scale = 0.3;
  // An episode fails when a body is this far from its reference (m); 0: the server's family
  // default (kFamilyDefaultTerminationDistance, 1 m).
  double termination_distance = 0;
  int max_iterations = 0;           // this process's; 0: no limit
  int64_t max_env_steps = 0;        // 0: no limit
  double max_minutes = 0;           // 0: no limit
  int net_every = 10;               // iterations between fits of P(a)
  uint64_t seed = 0;
  CoverageConfig coverage;
  CurriculumConfig curriculum;
  std::vector<int64_t> policy_hidden = {512, 256};
  std::vector<int64_t> value_hidden = {256, 256};
};

// What an iteration measured (a row of progress.csv).
struct FamilyIterationStats {
  int iteration = 0;
  int64_t env_steps = 0;
  double wall_s = 0;
  int episodes = 0;
  double mean_return = 0, mean_length = 0, mean_fitness = 0;
  int64_t elites = 0;
  double coverage = 0;
  double exploration_rate = 0;
  const char* mode = "exploration";
  double net_loss = 0;
  double approx_kl = 0;
  double learning_rate = 0;  // at the iteration's end
  double action_std = 0;     // the policy's exploration noise, exp(log_std) averaged over the actions
};

// progress.csv's header: FamilyIterationStats' fields in this order.
const std::vector<std::string>& FamilyProgressColumns();

// One evaluated episode at fixed parameters (FamilyTrainer::Evaluate).
struct FamilyRolloutResult {
  std::vector<double> params;  // a, in the parameters' units
  double apex_height = 0;      // m, the root's highest
  double highest_effector = 0;  // m, the highest an ankle, toe, wrist or hand got (a kick's foot)
  double flight_s = 0;         // s with every foot above its starting height + 3 cm
  double fitness = 0;          // F, the server's
  int steps = 0;
  bool reached_end = false;    // the clip's end, not a fall
};

class FamilyTrainer {
 public:
  // Checks the ranges and sizes, opens the session and builds the networks (or loads
  // run_dir/checkpoint.pt with resume). INVALID_ARGUMENT naming the field for bad settings.
  static absl::StatusOr<std::unique_ptr<FamilyTrainer>> Create(FamilyTrainerConfig config);
  ~FamilyTrainer();

  // Iterates until a limit or `stop()`; writes a checkpoint after every iteration.
  absl::Status Run(const std::function<bool()>& stop);
  absl::StatusOr<FamilyIterationStats> Iterate();
  // Ends the session cleanly (the destructor cancels it otherwise).
  absl::Status Close();

  // The policy's mean actions at each parameter vector (a, in units, inside the ranges), one
  // whole episode each on envs i = k mod len(params); the session then goes back to the
  // curriculum. DEADLINE_EXCEEDED when an episode does not end within max_steps.
  absl::StatusOr<std::vector<FamilyRolloutResult>> Evaluate(const std::vector<std::vector<double>>& params,
                                                            int max_steps = 1000);
  const ParamSpace& space() const { return *space_; }

  const EliteSet& elites() const { return *elites_; }
  FamilyActorCritic& model() { return model_; }
  ParameterizationNet& parameterization() { return net_; }
  int64_t env_steps() const { return env_steps_; }
  double learning_rate() const { return learning_rate_->rate(); }  // PPO's, as the KL steered it

 private:
  // One iteration's samples, [T] lists of [N] (or [N, ...]) tensors.
  struct Rollout {
    std::vector<torch::Tensor> obs, actions, log_probs, values, rewards, spikes, phase_steps, dones;
    torch::Tensor last_values;  // [N]
  };
  // One env's episode in progress: its return and the trajectory an elite would keep.
  struct EnvEpisode {
    double phase = 0;  // before the next step
    double total_reward = 0;
    int steps = 0;
    int batch_slot = 0;          // the curriculum vector the env was last given
    std::vector<float> phases;   // phase before each step
    std::vector<float> actions;  // [steps, A]: d clamped to [-1, 1], tau as log of the step taken
  };
  // The last step result's fields, float32 ([N] or [N, ...]; flags as 0/1).
  struct StepTensors {
    torch::Tensor obs, reward, spike, phase_step, done, truncated, fitness, ended_params;
  };
  explicit FamilyTrainer(FamilyTrainerConfig config);
  absl::StatusOr<StepTensors> ReadResult() const;
  absl::Status Open();
  absl::Status Collect(Rollout* rollout, FamilyIterationStats* stats);
  void RecordStep(int env, const float* action, float phase_step);
  absl::Status EndEpisode(int env, bool terminated, float fitness, const torch::Tensor& ended_params,
                          FamilyIterationStats* stats);
  absl::StatusOr<double> Update(const Rollout& rollout);  // -> mean approximate KL
  absl::Status AdvanceCurriculum();
  void AssignBatch();
  std::vector<double> Values(const std::vector<std::vector<double>>& params);
  double FitNet();
  absl::Status SaveCheckpoint() const;
  absl::Status ExportPolicyFile();  // run_dir/policy.pt
  absl::Status LoadCheckpoint();
  absl::Status AppendProgress(const FamilyIterationStats& stats);

  FamilyTrainerConfig config_;
  std::unique_ptr<CsvLogger> progress_;  // run_dir/progress.csv, a row per iteration
  std::unique_ptr<SimulationClient> client_;
  std::unique_ptr<SimulationStream> stream_;
  std::unique_ptr<ParamSpace> space_;
  std::vector<bool> free_dims_;  // false for a constraint
  std::unique_ptr<ParameterCurriculum> curriculum_;
  std::unique_ptr<EliteSet> elites_;
  FamilyActorCritic model_{nullptr};
  std::unique_ptr<torch::optim::Adam> optimizer_;
  std::unique_ptr<KlAdaptiveLearningRate> learning_rate_;
  ParameterizationNet net_{nullptr};
  std::unique_ptr<torch::optim::Adam> net_optimizer_;
  int obs_size_ = 0, action_size_ = 0, time_warp_ = 0, frames_ = 0, goal_start_ = 0;
  torch::Tensor obs_;           // [N, obs] the current observations
  torch::Tensor template_obs_;  // a first observation of an episode: V(a) for the curriculum
  std::vector<EnvEpisode> episodes_;
  CurriculumBatch batch_;
  int batch_episodes_ = 0, batch_new_elites_ = 0;
  int iteration_ = 0;
  int64_t env_steps_ = 0;
  double wall_s_ = 0;  // before this process (resume)
  double net_loss_ = 0;
  bool net_fitted_ = false;  // P(a) has been fitted to elites (policy.pt then carries it)
  std::mt19937_64 rng_;
};

}  // namespace modskill::learner::family

#endif  // MODSKILL_LEARNER_FAMILY_FAMILY_TRAINER_H_
