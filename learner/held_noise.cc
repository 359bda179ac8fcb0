#include "learner/held_noise.h"

namespace modskill::learner {

torch::Tensor HeldNoise::Next(size_t stream, int64_t rows, int64_t dims, torch::Generator& generator) {
  const torch::Tensor fresh = torch::randn({rows, dims}, generator);
  if (hold_steps_ <= 1) return fresh;
  if (noise_.size() <= stream) {
    noise_.resize(stream + 1);
    ended_.resize(stream + 1);
  }
  torch::Tensor& held = noise_[stream];
  if (!held.defined() || held.size(0) != rows || held.size(1) != dims) {
    held = fresh;  // a stream's first step, or its session reopened with another shape
    ended_[stream] = torch::zeros({rows}, torch::kBool);
    return held.clone();
  }
  torch::Tensor redraw = torch::rand({rows}, generator) < 1.0 / hold_steps_;
  if (ended_[stream].defined()) redraw = redraw | ended_[stream];
  held = torch::where(redraw.unsqueeze(1), fresh, held);
  ended_[stream] = torch::zeros({rows}, torch::kBool);
  return held.clone();
}

void HeldNoise::EpisodesEnded(size_t stream, const torch::Tensor& done) {
  if (hold_steps_ <= 1 || stream >= ended_.size() || !ended_[stream].defined()) return;
  if (done.numel() != ended_[stream].numel()) return;  // a reopened session: Next redraws every row
  ended_[stream] = ended_[stream] | (done.reshape({-1}) > 0.5);
}

}  // namespace modskill::learner
