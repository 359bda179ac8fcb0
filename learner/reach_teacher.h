// Behaviour cloning for a reach head (--task_teacher): a table of held reach poses
// (bench/reach_teacher.py) says where each skill holds the hand, relative to the root in its
// heading frame (the reach goal's frame, ReachTask::WriteGoal), and the z per part that holds it
// there. For a goal, the teacher's z is that of the entry whose point is nearest. The PPO update
// pulls the head's mean z toward it on the policy's own states (ppo_update.h), which gives the head
// the goal-to-z mapping that PPO alone does not find on the 2 m box (the reward of most targets
// barely changes with the arm); PPO's own gradient then refines it.
#ifndef MODSKILL_LEARNER_REACH_TEACHER_H_
#define MODSKILL_LEARNER_REACH_TEACHER_H_

#include <string>
#include <vector>

#include <torch/torch.h>

#include "absl/status/statusor.h"
#include "learner/model_config.h"

namespace modskill::learner {

class ReachTeacher {
 public:
  // The largest teacher file read (a table of a few thousand entries is a few MB).
  static constexpr size_t kMaxFileBytes = size_t{64} << 20;

  // Text: "#" comments, a "parts NAME..." line, an "embed_dim E" line, then one
  // "entry CLIP x y z" line per held pose followed by its parts' z (parts × E numbers). Each z
  // is normalized to the sphere. INVALID_ARGUMENT naming `origin` and the line otherwise.
  static absl::StatusOr<ReachTeacher> Parse(const std::string& text, const std::string& origin);
  // Reads and parses `path` (--task_teacher names it in errors).
  static absl::StatusOr<ReachTeacher> Load(const std::string& path);

  // The supervised parts as a mask over the policy's parts [P]: `task_parts` (all parts when empty).
  // FAILED_PRECONDITION naming --task_teacher when the teacher's parts or embed_dim are not the
  // policy's (`layout`'s parts, `embed_dim`: it was made from other skills), or when the layout's
  // goal is not a point (3 features).
  absl::StatusOr<torch::Tensor> PartMask(const NetworkLayout& layout, int64_t embed_dim,
                                         const std::vector<std::string>& task_parts) const;

  // goals [N, 3] (the reach goal: target − root, heading frame) -> the nearest entries' z [N, P, E].
  torch::Tensor NearestZ(const torch::Tensor& goals) const;

  int64_t size() const { return points_.size(0); }
  const std::vector<std::string>& parts() const { return parts_; }

 private:
  std::vector<std::string> parts_;
  torch::Tensor points_;  // [K, 3]
  torch::Tensor z_;       // [K, P, E], unit rows
};

// The teacher's loss on a minibatch: the mean over rows of Σ_parts mask_p ‖z_p − teacher_p‖², divided
// by the number of supervised parts. z, teacher [N, P, E]; part_mask [P].
torch::Tensor TeacherLoss(const torch::Tensor& z, const torch::Tensor& teacher, const torch::Tensor& part_mask);

// The teacher's weight after `env_steps`: `weight`, falling linearly to 0 at `fade_steps` (0: held).
double TeacherWeightAt(double weight, int64_t fade_steps, int64_t env_steps);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_REACH_TEACHER_H_
