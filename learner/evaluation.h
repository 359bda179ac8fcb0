// Evaluation as in the ModSkill and PHC papers: every clip once from its first frame with
// evaluation termination (mean body error > 0.5 m), through the server's Rollout RPC.
#ifndef MODSKILL_LEARNER_EVALUATION_H_
#define MODSKILL_LEARNER_EVALUATION_H_

#include <functional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/cpp/simulation_client.h"
#include "common/policy/policy_spec.h"

namespace modskill::learner {

struct EvaluationReport {
  std::string checkpoint;
  std::vector<v1::ClipMetrics> clips;
  std::vector<std::string> body_names;
  std::vector<std::string> part_names;
  double success_rate = 0;       // never terminated at 0.5 m
  double g_mpjpe_mm = 0;         // frame-weighted over all clips
  double mpjpe_mm = 0;
  double acc_error_mm = 0;
  double vel_error_mm = 0;
  std::vector<double> body_error_mm;  // per body, frame-weighted
  std::vector<double> part_error_mm;  // per part
  std::vector<std::pair<double, double>> success_at_distance;  // (m, rate) for 0.5, 0.45, ..., 0.2
  // A task that watches some bodies only (vr_tracking, TaskInfo.tracked_bodies): their names,
  // E_g-mpjpe over them and each one's error (frame-weighted). Succ is then the task's (it
  // terminates on them); every other figure stays the whole body's.
  std::vector<std::string> tracked_bodies;
  double tracked_g_mpjpe_mm = 0;
  std::vector<double> tracked_body_error_mm;

  std::string ToJson() const;
  // A table like Table 1 of the ModSkill paper, plus success vs termination distance and
  // per-part errors.
  std::string ToMarkdown(const std::string& method) const;
};

// Runs the TorchScript policy in `checkpoint_bytes` on `clips` (empty: all) on `client`'s server.
// With `on_frame` the server streams every simulated frame to it (for the viewer page).
absl::StatusOr<EvaluationReport> Evaluate(SimulationClient& client, const std::string& checkpoint_name,
                                          const std::string& checkpoint_bytes, const std::vector<std::string>& clips,
                                          const std::function<void(const v1::RolloutFrame&)>& on_frame = nullptr);

// The open-loop reference baseline: a zero policy in residual mode, so every PD target is the
// reference pose of the next frame. What a learned tracker must beat.
absl::StatusOr<std::string> OpenLoopReferencePolicy(const v1::EnvSpec& spec);

// Per clip, the steps a policy tracked and its E_mpjpe beside the baseline's (same clips).
std::string CompareWithBaseline(const EvaluationReport& policy, const EvaluationReport& baseline);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_EVALUATION_H_
