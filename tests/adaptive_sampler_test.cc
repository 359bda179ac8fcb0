// The adaptive clip sampler on its own: every scheme moves toward failing clips and back after
// successes, failure_rate weighs failures per step, the floor holds exactly, uniform never moves.
#include "server/core/curriculum/adaptive_sampler.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace modskill {
namespace {

using ::testing::HasSubstr;

double Sum(const std::vector<double>& p) { return std::accumulate(p.begin(), p.end(), 0.0); }

TEST(AdaptiveSamplerTest, ParsesSchemeNames) {
  EXPECT_EQ(*ParseSamplingScheme("uniform"), SamplingScheme::kUniform);
  EXPECT_EQ(*ParseSamplingScheme("failure_count"), SamplingScheme::kFailureCount);
  EXPECT_EQ(*ParseSamplingScheme("decay_on_success"), SamplingScheme::kDecayOnSuccess);
  EXPECT_EQ(*ParseSamplingScheme("failure_rate"), SamplingScheme::kFailureRate);
  for (SamplingScheme scheme : {SamplingScheme::kUniform, SamplingScheme::kFailureCount,
                                SamplingScheme::kDecayOnSuccess, SamplingScheme::kFailureRate}) {
    EXPECT_EQ(*ParseSamplingScheme(SamplingSchemeName(scheme)), scheme);
  }
  auto bad = ParseSamplingScheme("phc");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(bad.status().message()), HasSubstr("sampling: 'phc'"));
}

TEST(AdaptiveSamplerTest, ValidatesParametersNamingTheField) {
  EXPECT_TRUE(ValidateSamplingParameters(0.0, 1.0).ok());
  EXPECT_TRUE(ValidateSamplingParameters(1.0, 0.5).ok());
  auto floor = ValidateSamplingParameters(1.5, 0.999, "--sampling_floor");
  EXPECT_EQ(floor.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(floor.message()), HasSubstr("--sampling_floor: 1.5"));
  EXPECT_FALSE(ValidateSamplingParameters(-0.1, 0.999).ok());
  EXPECT_FALSE(ValidateSamplingParameters(std::nan(""), 0.999).ok());
  auto decay = ValidateSamplingParameters(0.2, 0.0);
  EXPECT_THAT(std::string(decay.message()), HasSubstr("sampling_decay"));
  EXPECT_FALSE(ValidateSamplingParameters(0.2, 1.01).ok());
}

TEST(AdaptiveSamplerTest, StartsUniform) {
  for (SamplingScheme scheme : {SamplingScheme::kUniform, SamplingScheme::kFailureCount,
                                SamplingScheme::kDecayOnSuccess, SamplingScheme::kFailureRate}) {
    AdaptiveSampler sampler(8, scheme);
    for (double p : sampler.Weights()) EXPECT_NEAR(p, 1.0 / 8, 1e-12);
  }
}

TEST(AdaptiveSamplerTest, FailureCountMovesTowardFailuresAndBackAfterSuccesses) {
  const int n = 10;
  AdaptiveSampler sampler(n, SamplingScheme::kFailureCount, 0.2);
  for (int k = 0; k < 3; ++k) sampler.Observe(4, /*failed=*/true);
  sampler.Observe(7, true);
  std::vector<double> p = sampler.Weights();
  EXPECT_NEAR(Sum(p), 1.0, 1e-12);
  EXPECT_NEAR(sampler.raw_weights()[4], 3 + kFailureCountEpsilon, 1e-12);
  EXPECT_GT(p[4], p[7]);
  EXPECT_GT(p[7], p[0]);
  EXPECT_GT(p[4], 0.5);
  // Probability ∝ failures above the floor: 3 : 1 (up to ε).
  EXPECT_NEAR(p[4] / p[7], 3.0, 0.01);
  // Successes of clip 4 decay its count: its probability falls step by step, back to uniform.
  double previous = p[4];
  for (int k = 0; k < 11; ++k) {
    sampler.Observe(4, false);
    const double now = sampler.Weights()[4];
    EXPECT_LT(now, previous) << k;
    previous = now;
  }
  EXPECT_LT(sampler.Weights()[4], sampler.Weights()[7]);  // count 3 * 0.9^11 = 0.94 < 1
  for (int k = 0; k < 200; ++k) {
    sampler.Observe(4, false);
    sampler.Observe(7, false);
  }
  for (double q : sampler.Weights()) EXPECT_NEAR(q, 1.0 / n, 1e-3);
}

TEST(AdaptiveSamplerTest, DecayOnSuccessMovesTowardFailuresAndBackAfterSuccesses) {
  const int n = 5;
  AdaptiveSampler sampler(n, SamplingScheme::kDecayOnSuccess, 0.2, 0.999);
  // Every clip succeeds 500 times: equal weights, still uniform.
  for (int k = 0; k < 500; ++k) {
    for (int c = 0; c < n; ++c) sampler.Observe(c, false);
  }
  for (double p : sampler.Weights()) EXPECT_NEAR(p, 1.0 / n, 1e-12);
  EXPECT_NEAR(sampler.raw_weights()[0], std::pow(0.999, 500), 1e-12);
  // A failure resets clip 2 to 1: it is now the most likely.
  sampler.Observe(2, true);
  EXPECT_DOUBLE_EQ(sampler.raw_weights()[2], 1.0);
  std::vector<double> p = sampler.Weights();
  EXPECT_NEAR(Sum(p), 1.0, 1e-12);
  for (int c = 0; c < n; ++c) {
    if (c != 2) EXPECT_GT(p[2], p[c]);
  }
  // Its successes bring it back.
  double previous = p[2];
  for (int k = 0; k < 500; ++k) {
    sampler.Observe(2, false);
    if (k % 100 == 99) {
      const double now = sampler.Weights()[2];
      EXPECT_LT(now, previous);
      previous = now;
    }
  }
  for (double q : sampler.Weights()) EXPECT_NEAR(q, 1.0 / n, 1e-12);
}

TEST(AdaptiveSamplerTest, FloorHoldsAfterAThousandFailuresOfOneClip) {
  for (SamplingScheme scheme : {SamplingScheme::kFailureCount, SamplingScheme::kDecayOnSuccess}) {
    for (double floor_fraction : {0.0, 0.05, 0.2, 0.5, 1.0}) {
      const int n = 20;
      AdaptiveSampler sampler(n, scheme, floor_fraction);
      for (int k = 0; k < 1000; ++k) {
        sampler.Observe(3, true);
        for (int c = 0; c < n; ++c) {
          if (c != 3) sampler.Observe(c, false);
        }
      }
      const std::vector<double> p = sampler.Weights();
      const double floor = floor_fraction / n;
      EXPECT_NEAR(Sum(p), 1.0, 1e-12);
      for (int c = 0; c < n; ++c) {
        EXPECT_GE(p[c], floor * (1 - 1e-12)) << SamplingSchemeName(scheme) << " floor " << floor_fraction;
        if (c != 3 && floor_fraction < 1) EXPECT_LT(p[c], p[3]);
      }
      if (scheme == SamplingScheme::kFailureCount && floor_fraction > 0) {
        // The scheme starves the other clips (weight ε against 1000): they sit exactly at the
        // floor and the failing clip gets everything else.
        for (int c = 0; c < n; ++c) {
          if (c != 3) EXPECT_NEAR(p[c], floor, 1e-12) << floor_fraction;
        }
        EXPECT_NEAR(p[3], 1 - (n - 1) * floor, 1e-12);
      }
      if (floor_fraction == 1.0) {
        for (double q : p) EXPECT_NEAR(q, 1.0 / n, 1e-12);
      }
    }
  }
}

// p_c = max(f, λ q_c): when flooring the smallest clip pushes a second one under the floor after
// the renormalization, that one is floored too and the floor still holds exactly.
TEST(AdaptiveSamplerTest, FloorIsExactAfterRenormalization) {
  AdaptiveSampler sampler(3, SamplingScheme::kFailureCount, 0.6);  // f = 0.2
  for (int k = 0; k < 8; ++k) sampler.Observe(0, true);             // count 8
  sampler.Observe(1, true);
  sampler.Observe(1, true);
  sampler.Observe(1, false);  // count 1.8: q_1 = 0.18 < f, and 0.8 * 1.801 / 9.802 = 0.147 after clamping clip 2
  std::vector<double> p = sampler.Weights();
  EXPECT_NEAR(p[0], 0.6, 1e-12);
  EXPECT_NEAR(p[1], 0.2, 1e-12);
  EXPECT_NEAR(p[2], 0.2, 1e-12);

  // One clip floored, the rest proportional to q: N = 4, f = 0.1, counts 3, 1, 0, 0.
  AdaptiveSampler four(4, SamplingScheme::kFailureCount, 0.4);
  for (int k = 0; k < 3; ++k) four.Observe(0, true);
  four.Observe(1, true);
  p = four.Weights();
  const double e = kFailureCountEpsilon;
  EXPECT_NEAR(p[0], 0.8 * (3 + e) / (4 + 2 * e), 1e-12);
  EXPECT_NEAR(p[1], 0.8 * (1 + e) / (4 + 2 * e), 1e-12);
  EXPECT_NEAR(p[2], 0.1, 1e-12);
  EXPECT_NEAR(p[3], 0.1, 1e-12);
}

TEST(AdaptiveSamplerTest, RandomReportsKeepTheFloorTheSumAndTheOrder) {
  std::mt19937_64 rng(7);
  for (SamplingScheme scheme :
       {SamplingScheme::kFailureCount, SamplingScheme::kDecayOnSuccess, SamplingScheme::kFailureRate}) {
    const int n = 50;
    AdaptiveSampler sampler(n, scheme, 0.3, 0.99);
    std::uniform_int_distribution<int> clip(0, n - 1);
    for (int k = 0; k < 5000; ++k) {
      const int c = clip(rng);
      sampler.Observe(c, (rng() % 100) < static_cast<unsigned>(c));  // clip c fails c % of the time
      if (k % 500 != 499) continue;
      const std::vector<double> p = sampler.Weights();
      EXPECT_NEAR(Sum(p), 1.0, 1e-9);
      const std::vector<double>& w = sampler.raw_weights();
      for (int a = 0; a < n; ++a) {
        EXPECT_GE(p[a], 0.3 / n * (1 - 1e-12));
        for (int b = 0; b < n; ++b) {
          if (w[a] > w[b]) EXPECT_GE(p[a], p[b]);
        }
      }
    }
  }
}

// Every episode of a long clip and of a short one fails, the long one after 150 steps, the
// short one after 20; a third clip is tracked to its end every 30 steps. failure_count cannot
// tell the first two apart; failure_rate draws the short one about 150 / 20 times as often.
TEST(AdaptiveSamplerTest, FailureRateWeighsFailuresPerStep) {
  AdaptiveSampler count(3, SamplingScheme::kFailureCount, 0.0);
  AdaptiveSampler rate(3, SamplingScheme::kFailureRate, 0.0);
  for (int k = 0; k < 400; ++k) {
    for (AdaptiveSampler* sampler : {&count, &rate}) {
      sampler->Observe(0, /*failed=*/true, /*steps=*/150);
      sampler->Observe(1, true, 20);
      sampler->Observe(2, false, 30);
    }
  }
  const std::vector<double> p_count = count.Weights();
  EXPECT_NEAR(p_count[0], p_count[1], 1e-9);
  const std::vector<double>& w = rate.raw_weights();
  // The moving sums converge to 100 reports' worth: (100 + 1) / (100 * L + 30).
  EXPECT_NEAR(w[0], 101.0 / (100 * 150 + 30), 1e-4);
  EXPECT_NEAR(w[1], 101.0 / (100 * 20 + 30), 1e-3);
  EXPECT_NEAR(w[2], 1.0 / (100 * 30 + 30), 1e-4);
  const std::vector<double> p_rate = rate.Weights();
  EXPECT_NEAR(p_rate[1] / p_rate[0], 7.4, 0.1);
  EXPECT_GT(p_rate[0], 10 * p_rate[2]);
  EXPECT_NEAR(Sum(p_rate), 1.0, 1e-12);
}

// A report without its length counts the clip's recent mean length, or the prior's 30 steps.
TEST(AdaptiveSamplerTest, FailureRateTakesUnknownLengthsAsTheClipsMean) {
  AdaptiveSampler known(2, SamplingScheme::kFailureRate);
  AdaptiveSampler unknown(2, SamplingScheme::kFailureRate);
  for (int k = 0; k < 10; ++k) {
    known.Observe(0, true, 40);
    unknown.Observe(0, true, 40);
  }
  known.Observe(0, true, 40);
  unknown.Observe(0, true, 0);
  EXPECT_NEAR(known.raw_weights()[0], unknown.raw_weights()[0], 1e-12);
  unknown.Observe(1, true, -5);  // nothing known about clip 1 yet: the prior's length
  EXPECT_NEAR(unknown.raw_weights()[1], 2.0 / 60.0, 1e-12);
}

TEST(AdaptiveSamplerTest, FailureRateRemapKeepsSumsAndStartsNewClipsAtThePrior) {
  AdaptiveSampler sampler(2, SamplingScheme::kFailureRate);
  for (int k = 0; k < 50; ++k) sampler.Observe(1, true, 10);
  const double failing = sampler.raw_weights()[1];
  sampler.Remap({1, -1, 0}, /*new_clip_count=*/5.0);
  ASSERT_EQ(sampler.num_clips(), 3);
  EXPECT_DOUBLE_EQ(sampler.raw_weights()[0], failing);
  EXPECT_DOUBLE_EQ(sampler.raw_weights()[1], kFailureRatePriorFailures / kFailureRatePriorSteps);
  EXPECT_DOUBLE_EQ(sampler.raw_weights()[2], kFailureRatePriorFailures / kFailureRatePriorSteps);
  sampler.Observe(0, true, 10);  // the carried sums go on: one more report as before the remap
  EXPECT_GT(sampler.raw_weights()[0], failing);
}

TEST(AdaptiveSamplerTest, UniformNeverMoves) {
  AdaptiveSampler sampler(6, SamplingScheme::kUniform, 0.0);
  for (int k = 0; k < 1000; ++k) {
    sampler.Observe(1, true);
    sampler.Observe(2, false);
  }
  for (double p : sampler.Weights()) EXPECT_DOUBLE_EQ(p, 1.0 / 6);
  for (double w : sampler.raw_weights()) EXPECT_DOUBLE_EQ(w, 1.0);
}

TEST(AdaptiveSamplerTest, IgnoresUnknownClipsAndHandlesOneClip) {
  AdaptiveSampler sampler(3, SamplingScheme::kFailureCount);
  sampler.Observe(-1, true);
  sampler.Observe(3, true);
  for (double p : sampler.Weights()) EXPECT_NEAR(p, 1.0 / 3, 1e-12);
  AdaptiveSampler one(1, SamplingScheme::kDecayOnSuccess);
  one.Observe(0, true);
  EXPECT_EQ(one.Weights(), std::vector<double>{1.0});
}

}  // namespace
}  // namespace modskill
