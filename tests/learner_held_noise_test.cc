// HeldNoise: rows keep their noise for a geometric number of steps of the asked mean, redraw when
// their episode ends, and every step's noise is still standard normal.
#include "learner/held_noise.h"

#include <gtest/gtest.h>

namespace modskill::learner {
namespace {

// Steps a row kept its noise from the step before, over `steps` steps of 256 rows.
double MeanHold(int hold_steps, int steps) {
  HeldNoise noise(hold_steps);
  torch::Generator generator = at::detail::createCPUGenerator(11);
  torch::Tensor last = noise.Next(0, 256, 4, generator);
  int64_t kept = 0;
  for (int s = 0; s < steps; ++s) {
    const torch::Tensor next = noise.Next(0, 256, 4, generator);
    kept += (next == last).all(1).sum().item<int64_t>();
    last = next;
  }
  const double keep_probability = static_cast<double>(kept) / (256.0 * steps);
  return 1.0 / (1.0 - keep_probability);  // the geometric hold's mean
}

TEST(HeldNoiseTest, HoldsForTheAskedMeanNumberOfSteps) {
  EXPECT_NEAR(MeanHold(1, 50), 1.0, 1e-9);  // fresh every step: no row repeats
  EXPECT_NEAR(MeanHold(5, 400), 5.0, 0.25);
  EXPECT_NEAR(MeanHold(20, 800), 20.0, 2.0);
}

TEST(HeldNoiseTest, EndedEpisodesRedrawAndStreamsAreSeparate) {
  HeldNoise noise(1000000);  // held for all practical purposes
  torch::Generator generator = at::detail::createCPUGenerator(3);
  const torch::Tensor first = noise.Next(0, 4, 3, generator);
  const torch::Tensor other = noise.Next(1, 2, 3, generator);
  noise.EpisodesEnded(0, torch::tensor({0.f, 1.f, 0.f, 0.f}));
  const torch::Tensor second = noise.Next(0, 4, 3, generator);
  EXPECT_TRUE(torch::equal(second[0], first[0]));
  EXPECT_FALSE(torch::equal(second[1], first[1]));  // its episode ended
  EXPECT_TRUE(torch::equal(second.narrow(0, 2, 2), first.narrow(0, 2, 2)));
  EXPECT_TRUE(torch::equal(noise.Next(1, 2, 3, generator), other));  // stream 1 saw no episode end
  // A stream whose session reopened with another size starts over instead of failing.
  EXPECT_EQ(noise.Next(0, 6, 3, generator).size(0), 6);
}

TEST(HeldNoiseTest, EachStepIsStandardNormal) {
  HeldNoise noise(8);
  torch::Generator generator = at::detail::createCPUGenerator(5);
  std::vector<torch::Tensor> steps;
  for (int s = 0; s < 200; ++s) steps.push_back(noise.Next(0, 512, 2, generator));
  const torch::Tensor all = torch::stack(steps);
  EXPECT_NEAR(all.mean().item<double>(), 0.0, 0.05);
  EXPECT_NEAR(all.std().item<double>(), 1.0, 0.05);
}

}  // namespace
}  // namespace modskill::learner
