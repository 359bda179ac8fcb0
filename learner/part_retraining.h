// Starting a tracker from an exported one and retraining some of its parts only (ModSkill's
// modularity, issue 13 item 4): `--init_from TRACKER/policy.pt --train_parts R_Arm,L_Arm` loads
// the tracker's skill attention, part controllers and observation statistics; the named parts'
// controllers and attention maps (key, query, value) train on the new clips while every other
// part's stay exactly as they were (requires_grad false, so the optimizer leaves them out) and the
// normalizer keeps the tracker's statistics, so a frozen controller reads what it always read.
// Without --train_parts every part trains (a tracker continued on new clips). With
// train_attention false the named parts' controllers train alone: every part's z then stays the
// tracker's (the attention mixes every part's key and value into each part's z, so a retrained
// map moves the frozen parts' z too). With fresh_parts the named parts start from fresh weights, as
// a part new to the tracker would (a new controller, and new attention maps when they train).
#ifndef MODSKILL_LEARNER_PART_RETRAINING_H_
#define MODSKILL_LEARNER_PART_RETRAINING_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "common/policy/action_mode.h"
#include "learner/model_config.h"
#include "learner/modskill_policy.h"
#include "learner/running_mean_std.h"

namespace modskill::learner {

struct RetrainedTracker {
  ModSkillPolicy policy{nullptr};
  RunningMeanStd obs_norm{nullptr};
  std::vector<int> trained_parts;  // layout indices; every part without --train_parts
};

// INVALID_ARGUMENT naming --init_from for a file that is not a tracker's policy.pt, or
// --train_parts[i] for a name that is not a part of `layout` (or given twice);
// FAILED_PRECONDITION naming --init_from when the tracker was trained on another layout,
// observation or action mapping than this run's, or when parts are named for a whole-body tracker.
absl::StatusOr<RetrainedTracker> LoadTrackerForRetraining(const std::string& path, const std::vector<std::string>& train_parts,
                                                          const std::string& layout_name, const NetworkLayout& layout,
                                                          const ActionMapping& action, bool train_attention = true,
                                                          bool fresh_parts = false);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_PART_RETRAINING_H_
