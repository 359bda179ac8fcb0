// Exploration noise that an env keeps for several control steps. A task head's z moves the body
// through PD controllers that average a step's noise away, so per-step noise barely changes what
// the hand does and PPO sees no advantage in it; held noise moves the body for long enough to
// matter (gSDE and colored-noise exploration; PPO keeps the per-step Gaussian likelihood, whose
// marginal the held noise still follows).
#ifndef MODSKILL_LEARNER_HELD_NOISE_H_
#define MODSKILL_LEARNER_HELD_NOISE_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

namespace modskill::learner {

class HeldNoise {
 public:
  // hold_steps >= 1: a row keeps its noise each step with probability 1 - 1 / hold_steps (a
  // geometric hold of mean hold_steps); 1 draws fresh noise every step.
  explicit HeldNoise(int hold_steps) : hold_steps_(hold_steps) {}

  // Standard normal noise [rows, dims] for the next step of `stream` (an index the caller keeps
  // for each session): the last step's row where it is held, a fresh draw otherwise.
  torch::Tensor Next(size_t stream, int64_t rows, int64_t dims, torch::Generator& generator);
  // Rows of `stream` whose episode ended (done [rows] > 0.5) draw fresh noise next step.
  void EpisodesEnded(size_t stream, const torch::Tensor& done);

 private:
  int hold_steps_;
  std::vector<torch::Tensor> noise_;   // per stream, [rows, dims]; undefined before its first step
  std::vector<torch::Tensor> ended_;   // per stream, [rows] bool
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_HELD_NOISE_H_
