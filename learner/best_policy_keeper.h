// A score-based export, as ProtoMotions keeps beside its last checkpoint: every `every` iterations
// the run's policy is evaluated with the paper's protocol on the run's clips (the server's Rollout,
// exactly what `--eval` runs), and the best policy so far is kept as run_dir/policy_best.pt, its
// evaluation beside it as policy_best.md and policy_best.json (with its iteration and env steps).
// PPO's weights wander from update to update, and one export is one draw from that wander
// (docs/performance/learning.md: 19-22 consecutive exports on cmu_02_01 span 26-42 mm of E_mpjpe); the
// evaluation is deterministic, so the kept file scores what it scored.
// Best: more clips tracked to their end, then the lower E_mpjpe + E_g-mpjpe. Every evaluation is
// a row of run_dir/evaluations.csv: the run's evaluation curve.
#ifndef MODSKILL_LEARNER_BEST_POLICY_KEEPER_H_
#define MODSKILL_LEARNER_BEST_POLICY_KEEPER_H_

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/cpp/simulation_client.h"
#include "learner/evaluation.h"
#include "learner/tensorboard_writer.h"
#include "learner/trainer.h"

namespace modskill::learner {

struct PolicyScore {
  double success_rate = 0;
  double mpjpe_mm = 0;
  double g_mpjpe_mm = 0;
  int iteration = 0;
  int64_t env_steps = 0;

  // More clips tracked, then the smaller E_mpjpe + E_g-mpjpe.
  bool BetterThan(const PolicyScore& other) const;
};

class BestPolicyKeeper {
 public:
  // `client`: a server with the run's clips and physics (the run's first). A fresh run drops a
  // policy_best.pt left in run_dir by an earlier one; a resumed run scores the one it left (the
  // evaluation is deterministic), so that a later draw replaces it only when it is better (one
  // the server cannot evaluate is replaced by the next draw).
  // INVALID_ARGUMENT (see CheckSettings) for `every` < 1 or a task run.
  static absl::StatusOr<std::unique_ptr<BestPolicyKeeper>> Create(const Trainer& trainer, SimulationClient* client,
                                                                  int every);

  // INVALID_ARGUMENT, naming --keep_best_every, for `every` < 1 or a task run (only a tracker
  // follows every clip from its start). The CLI checks it before any session opens.
  static absl::Status CheckSettings(const TrainerConfig& config, int every);

  // After an iteration: when it is due, exports and evaluates the policy and keeps it if it is the
  // best so far. The error of an evaluation (a server gone, say) is returned; the run may go on.
  absl::Status AfterIteration(Trainer& trainer);

  const std::optional<PolicyScore>& best() const { return best_; }
  // Every evaluation of this run so far, in order (for reports and tests).
  const std::vector<PolicyScore>& scores() const { return scores_; }
  std::string best_path() const { return run_dir_ + "/policy_best.pt"; }

 private:
  BestPolicyKeeper(SimulationClient* client, int every, std::string run_dir, std::vector<std::string> clips,
                   std::unique_ptr<CsvLogger> curve)
      : client_(client), every_(every), run_dir_(std::move(run_dir)), clips_(std::move(clips)), curve_(std::move(curve)) {}
  absl::StatusOr<EvaluationReport> EvaluateFile(const std::string& path);

  SimulationClient* client_;
  int every_;
  std::string run_dir_;
  std::vector<std::string> clips_;
  std::unique_ptr<CsvLogger> curve_;  // evaluations.csv
  std::optional<PolicyScore> best_;
  std::vector<PolicyScore> scores_;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_BEST_POLICY_KEEPER_H_
