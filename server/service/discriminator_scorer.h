// The learner's AMP discriminator on the server side: scores how much a generated clip's
// motion looks like the reference data (ReportFailuresRequest.discriminator), for the
// plausibility filter's discriminator check (ModSkill keeps a generated clip only if the score
// is >= 0.5 on 30 random frames).
#ifndef MODSKILL_SERVER_SERVICE_DISCRIMINATOR_SCORER_H_
#define MODSKILL_SERVER_SERVICE_DISCRIMINATOR_SCORER_H_

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/env/env_spec.h"
#include "server/core/motion/motion_clip.h"

namespace torch::jit {
struct Module;
}  // namespace torch::jit

namespace modskill {

class DiscriminatorScorer {
 public:
  // Loads a TorchScript archive and checks it on a zero batch: forward([2, amp_width]) must give
  // 2 finite scores in [0, 1]. Errors name `discriminator`.
  static absl::StatusOr<std::shared_ptr<const DiscriminatorScorer>> LoadBytes(absl::string_view bytes, int amp_width);
  ~DiscriminatorScorer();

  // Scores `count` AMP observations of `clip` (random frames from `seed`; `clip` needs its
  // kinematics). Not thread safe: one caller at a time (the generation worker).
  absl::StatusOr<std::vector<float>> ScoreClip(const EnvSpec& spec, const MotionClip& clip, int count,
                                               uint64_t seed) const;

 private:
  DiscriminatorScorer() = default;
  std::unique_ptr<torch::jit::Module> module_;
  int amp_width_ = 0;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_DISCRIMINATOR_SCORER_H_
