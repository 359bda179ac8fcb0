#include "server/service/discriminator_scorer.h"

#include <cmath>
#include <random>
#include <sstream>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "server/core/env/reference_amp.h"
#include "server/core/motion/motion_library.h"

namespace modskill {
namespace {

// The scores of a [N, amp_width] batch, checked: N finite values in [0, 1].
absl::StatusOr<std::vector<float>> Run(torch::jit::Module& module, torch::Tensor batch) {
  torch::NoGradGuard no_grad;
  torch::Tensor out;
  try {
    out = module.forward({batch}).toTensor().to(torch::kFloat).reshape({-1}).contiguous();
  } catch (const std::exception& e) {
    const std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat("discriminator: forward failed: ", message.substr(0, message.find('\n'))));
  }
  if (out.numel() != batch.size(0)) {
    return absl::InvalidArgumentError(
        absl::StrCat("discriminator: ", out.numel(), " scores for a batch of ", batch.size(0)));
  }
  std::vector<float> scores(out.data_ptr<float>(), out.data_ptr<float>() + out.numel());
  for (float s : scores) {
    if (!std::isfinite(s) || s < 0 || s > 1) {
      return absl::InvalidArgumentError(absl::StrCat("discriminator: score ", s, " outside [0, 1]"));
    }
  }
  return scores;
}

}  // namespace

DiscriminatorScorer::~DiscriminatorScorer() = default;

absl::StatusOr<std::shared_ptr<const DiscriminatorScorer>> DiscriminatorScorer::LoadBytes(absl::string_view bytes,
                                                                                          int amp_width) {
  std::shared_ptr<DiscriminatorScorer> scorer(new DiscriminatorScorer());
  scorer->amp_width_ = amp_width;
  try {
    std::istringstream in(std::string(bytes), std::ios::binary);
    scorer->module_ = std::make_unique<torch::jit::Module>(torch::jit::load(in));
    scorer->module_->eval();
  } catch (const std::exception& e) {
    const std::string message = e.what();
    return absl::InvalidArgumentError(
        absl::StrCat("discriminator: not a TorchScript archive: ", message.substr(0, message.find('\n'))));
  }
  auto probe = Run(*scorer->module_, torch::zeros({2, amp_width}));
  if (!probe.ok()) return probe.status();
  return std::shared_ptr<const DiscriminatorScorer>(std::move(scorer));
}

absl::StatusOr<std::vector<float>> DiscriminatorScorer::ScoreClip(const EnvSpec& spec, const MotionClip& clip,
                                                                   int count, uint64_t seed) const {
  MotionLibrary library;
  if (absl::Status status = library.Add(clip); !status.ok()) return status;
  const ReferenceAmpFrames frames(spec, library);
  if (kAmpHistory * frames.per_frame() != amp_width_) {
    return absl::FailedPreconditionError(absl::StrCat("discriminator: takes ", amp_width_, " values, the session's ",
                                                      "AMP observation has ", kAmpHistory * frames.per_frame()));
  }
  torch::Tensor batch = torch::empty({count, amp_width_}, torch::kFloat);
  std::mt19937_64 rng(seed);
  frames.Sample(count, rng, batch.data_ptr<float>());
  return Run(*module_, batch);
}

}  // namespace modskill
