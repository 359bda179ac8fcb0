// GAE, PPO's loss, AMP's loss and reward against hand-computed cases, and the training logs
// (TensorBoard event files parsed back byte by byte, CSV resume).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/torch.h>

#include "absl/strings/string_view.h"
#include "learner/amp_loss.h"
#include "learner/gae.h"
#include "learner/kl_adaptive_learning_rate.h"
#include "learner/learning_rate_decay.h"
#include "learner/ppo_loss.h"
#include "learner/tensorboard_writer.h"
#include "learner/termination_curriculum.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;

torch::Tensor T(std::vector<float> values) { return torch::tensor(values); }

void ExpectTensorNear(const torch::Tensor& actual, const torch::Tensor& expected,
                      double tolerance = 1e-5) {
  ASSERT_EQ(actual.sizes(), expected.sizes());
  EXPECT_TRUE(torch::allclose(actual, expected, /*rtol=*/0, tolerance))
      << "actual\n" << actual << "\nexpected\n" << expected;
}

// A fresh directory per test and per process under the build's tmp dir (so that concurrent
// runs of this binary never share files), removed after the test.
class TempDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = std::filesystem::path(MODSKILL_TEST_TMP_DIR) / "learner_algorithms_test" /
           (std::string(info->name()) + "." + std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
  std::filesystem::path dir_;
};
using TensorBoardWriterTest = TempDirTest;
using CsvLoggerTest = TempDirTest;

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

// ------------------------------------------------------------------------------------------
// GAE

TEST(GaeTest, HandComputedWithDoneInTheMiddle) {
  // gamma = 0.9, lambda = 0.8, so gamma * lambda = 0.72. Rows are time, columns envs.
  // env 0: r = [1, 2, 3], V = [0.5, 1.0, 1.5], done after t = 1, V(s_3) = 2.0
  //   t=2: delta = 3 + 0.9 * 2.0 - 1.5 = 3.3                      A = 3.3
  //   t=1: delta = 2 + 0 (done)  - 1.0 = 1.0                       A = 1.0 (no carry)
  //   t=0: delta = 1 + 0.9 * 1.0 - 0.5 = 1.4                      A = 1.4 + 0.72 * 1.0 = 2.12
  // env 1: r = [0.5, -1, 1], V = [1, 2, 0], no done, V(s_3) = -1
  //   t=2: delta = 1 + 0.9 * -1 - 0    = 0.1                      A = 0.1
  //   t=1: delta = -1 + 0.9 * 0 - 2    = -3                       A = -3 + 0.72 * 0.1 = -2.928
  //   t=0: delta = 0.5 + 0.9 * 2 - 1   = 1.3                      A = 1.3 + 0.72 * -2.928
  //                                                                 = -0.80816
  const torch::Tensor rewards = torch::tensor({{1.0f, 0.5f}, {2.0f, -1.0f}, {3.0f, 1.0f}});
  const torch::Tensor values = torch::tensor({{0.5f, 1.0f}, {1.0f, 2.0f}, {1.5f, 0.0f}});
  const torch::Tensor dones = torch::tensor({{0.0f, 0.0f}, {1.0f, 0.0f}, {0.0f, 0.0f}});
  const torch::Tensor last_values = T({2.0f, -1.0f});
  torch::Tensor advantages, returns;
  ComputeGae(rewards, values, dones, last_values, 0.9, 0.8, &advantages, &returns);

  const torch::Tensor expected =
      torch::tensor({{2.12f, -0.80816f}, {1.0f, -2.928f}, {3.3f, 0.1f}});
  ExpectTensorNear(advantages, expected);
  // returns = A + V: env 0 [2.62, 2.0, 4.8], env 1 [0.19184, -0.928, 0.1].
  ExpectTensorNear(returns, torch::tensor({{2.62f, 0.19184f}, {2.0f, -0.928f}, {4.8f, 0.1f}}));
  ExpectTensorNear(returns, advantages + values);
}

TEST(GaeTest, DoneOnTheLastStepIgnoresLastValues) {
  // delta = 1 + 0 (done) - 0.5 = 0.5; V(s_1) = 100 must not leak in.
  torch::Tensor advantages, returns;
  ComputeGae(torch::tensor({{1.0f}}), torch::tensor({{0.5f}}), torch::tensor({{1.0f}}),
             T({100.0f}), 0.99, 0.95, &advantages, &returns);
  EXPECT_NEAR(advantages.item<double>(), 0.5, 1e-6);
  EXPECT_NEAR(returns.item<double>(), 1.0, 1e-6);
}

TEST(GaeTest, LambdaOneIsDiscountedReturnMinusValue) {
  // lambda = 1, gamma = 0.5, no done: A_0 = r0 + 0.5 r1 + 0.25 V(s_2) - V_0
  //   = 1 + 0.5 * 2 + 0.25 * 4 - 3 = 0.
  torch::Tensor advantages, returns;
  ComputeGae(torch::tensor({{1.0f}, {2.0f}}), torch::tensor({{3.0f}, {7.0f}}),
             torch::zeros({2, 1}), T({4.0f}), 0.5, 1.0, &advantages, &returns);
  EXPECT_NEAR(advantages[0].item<double>(), 0.0, 1e-6);
  EXPECT_NEAR(returns[0].item<double>(), 3.0, 1e-6);
}

// ------------------------------------------------------------------------------------------
// PPO

TEST(PpoLossTest, ClippedSurrogateHandComputed) {
  // clip = 0.2, so ratios are clipped to [0.8, 1.2]. old_log_prob = 0, new = log(ratio).
  //   ratio A    ratio*A  clip(ratio)*A  min    which
  //   1.5   +1   1.5      1.2            1.2    clipped (no gradient)
  //   0.5   +1   0.5      0.8            0.5    unclipped (pessimistic side)
  //   1.1   -2  -2.2     -2.2           -2.2    inside the trust region
  //   0.7   -1  -0.7     -0.8           -0.8    clipped (no gradient)
  //   1.3   -1  -1.3     -1.2           -1.3    unclipped (pessimistic side)
  // policy_loss = -(1.2 + 0.5 - 2.2 - 0.8 - 1.3) / 5 = 2.6 / 5 = 0.52
  const std::vector<float> ratios = {1.5f, 0.5f, 1.1f, 0.7f, 1.3f};
  const torch::Tensor new_log_prob = T(ratios).log().requires_grad_(true);
  const torch::Tensor old_log_prob = torch::zeros({5});
  const torch::Tensor advantages = T({1, 1, -2, -1, -1});
  // Values equal to the returns: value_loss = 0, so total = policy_loss.
  const torch::Tensor values = T({1, 2, 3, 4, 5});
  const PpoLossTerms terms = ComputePpoLoss(new_log_prob, old_log_prob, advantages, values,
                                            values, values, 0.2, 0.5, 0.5);
  EXPECT_NEAR(terms.policy_loss.item<double>(), 0.52, 1e-5);
  EXPECT_NEAR(terms.value_loss.item<double>(), 0.0, 1e-7);
  EXPECT_NEAR(terms.total.item<double>(), 0.52, 1e-5);

  // approx_kl = mean(old - new) = -log(1.5 * 0.5 * 1.1 * 0.7 * 1.3) / 5 = -log(0.75075) / 5
  //           = 0.0573366.
  EXPECT_NEAR(terms.approx_kl.item<double>(), -std::log(0.75075) / 5, 1e-5);
  EXPECT_NEAR(terms.approx_kl.item<double>(), 0.0573366, 1e-5);
  // |ratio - 1| > 0.2 for 1.5, 0.5, 0.7, 1.3: 4 of 5.
  EXPECT_NEAR(terms.clip_fraction.item<double>(), 0.8, 1e-6);
  EXPECT_FALSE(terms.approx_kl.requires_grad());
  EXPECT_FALSE(terms.clip_fraction.requires_grad());

  // d policy_loss / d log pi = -ratio * A / 5 where the unclipped term is the min, else 0:
  //   [0, -0.5 / 5, 2.2 / 5, 0, 1.3 / 5] = [0, -0.1, 0.44, 0, 0.26].
  terms.total.backward();
  ExpectTensorNear(new_log_prob.grad(), T({0.0f, -0.1f, 0.44f, 0.0f, 0.26f}));
}

TEST(PpoLossTest, ValueLossClippedAndUnclipped) {
  // value_clip = 0.5, old V = 1 everywhere.
  //   new V  R   (V-R)^2  V_clipped = 1 + clamp(V-1, +-0.5)  (V_clip-R)^2  max
  //   2      3   1        1.5                                 2.25          2.25 (clipped)
  //   1.2    0   1.44     1.2                                 1.44          1.44
  //   0      1   1        0.5                                 0.25          1    (unclipped)
  // value_loss = 0.5 * (2.25 + 1.44 + 1) / 3 = 0.5 * 4.69 / 3 = 0.781667
  const torch::Tensor new_values = T({2.0f, 1.2f, 0.0f}).requires_grad_(true);
  const torch::Tensor old_values = T({1, 1, 1});
  const torch::Tensor returns = T({3, 0, 1});
  const torch::Tensor zeros = torch::zeros({3});  // policy term 0: ratio 1, A 0
  const PpoLossTerms terms =
      ComputePpoLoss(zeros, zeros, zeros, new_values, old_values, returns, 0.2, 0.5, 2.0);
  EXPECT_NEAR(terms.value_loss.item<double>(), 0.5 * 4.69 / 3, 1e-5);
  EXPECT_NEAR(terms.policy_loss.item<double>(), 0.0, 1e-7);
  EXPECT_NEAR(terms.total.item<double>(), 2.0 * 0.5 * 4.69 / 3, 1e-5);  // c_v = 2
  EXPECT_NEAR(terms.clip_fraction.item<double>(), 0.0, 1e-7);
  EXPECT_NEAR(terms.approx_kl.item<double>(), 0.0, 1e-7);

  // Gradient of 2 * 0.5 * mean(.) w.r.t. V: the clipped sample gives 0;
  // else 2 * 0.5 * 2 * (V - R) / 3 = [0, 2.4 / 3, -2 / 3] = [0, 0.8, -0.666667].
  terms.total.backward();
  ExpectTensorNear(new_values.grad(), T({0.0f, 0.8f, -2.0f / 3.0f}));

  // value_clip = 0 turns clipping off: 0.5 * (1 + 1.44 + 1) / 3 = 0.573333.
  const PpoLossTerms unclipped =
      ComputePpoLoss(zeros, zeros, zeros, new_values, old_values, returns, 0.2, 0.0, 2.0);
  EXPECT_NEAR(unclipped.value_loss.item<double>(), 0.5 * 3.44 / 3, 1e-5);
}

TEST(PpoLossTest, NormalizeAdvantages) {
  // mean 2.5, population std sqrt(1.25) = 1.118034.
  ExpectTensorNear(NormalizeAdvantages(T({1, 2, 3, 4})),
                   T({-1.341641f, -0.447214f, 0.447214f, 1.341641f}));
  ExpectTensorNear(NormalizeAdvantages(T({7})), T({0}));
  const torch::Tensor a = T({1, 2}).requires_grad_(true);
  EXPECT_FALSE(NormalizeAdvantages(a).requires_grad());
}

TEST(PpoLossTest, DecoupledAdvantagesWeighTowardTheProximalPolicy) {
  // pi_prox / pi_behaviour = e^-1, 1 and e^2 (truncated at 1): weights 0.3679, 1, 1.
  const torch::Tensor advantages = T({2, -3, 4});
  const torch::Tensor behaviour = T({-1, -2, -5});
  const torch::Tensor proximal = T({-2, -2, -3});
  ExpectTensorNear(DecoupledAdvantages(advantages, proximal, behaviour), T({0.735759f, -3, 4}));
  // A larger truncation lets the third weight through.
  ExpectTensorNear(DecoupledAdvantages(advantages, proximal, behaviour, 10.0), T({0.735759f, -3, 29.556224f}));
  EXPECT_FALSE(DecoupledAdvantages(advantages.requires_grad_(true), proximal, behaviour).requires_grad());
}

// ------------------------------------------------------------------------------------------
// AMP

TEST(KlAdaptiveLearningRateTest, StepsDownOnLargeKlUpOnSmallAndStaysInBounds) {
  KlAdaptiveLearningRate rate(3e-4, 0.01);
  EXPECT_NEAR(rate.Update(0.05), 2e-4, 1e-12);      // above 2 x target: / 1.5
  EXPECT_NEAR(rate.Update(0.015), 2e-4, 1e-12);     // within [target / 2, 2 x target]: kept
  EXPECT_NEAR(rate.Update(0.001), 3e-4, 1e-12);     // below target / 2: x 1.5
  for (int i = 0; i < 100; ++i) rate.Update(1.0);
  EXPECT_DOUBLE_EQ(rate.rate(), KlAdaptiveLearningRate::kMinRate);
  for (int i = 0; i < 100; ++i) rate.Update(0.0);
  EXPECT_DOUBLE_EQ(rate.rate(), KlAdaptiveLearningRate::kMaxRate);
  KlAdaptiveLearningRate fixed(3e-4, 0.0);
  EXPECT_DOUBLE_EQ(fixed.Update(5.0), 3e-4);

  torch::Tensor weight = torch::zeros({2}, torch::requires_grad());
  torch::optim::Adam adam({weight}, torch::optim::AdamOptions(1e-3));
  rate.set_rate(2e-5);
  rate.ApplyTo(adam);
  EXPECT_DOUBLE_EQ(static_cast<torch::optim::AdamOptions&>(adam.param_groups()[0].options()).lr(), 2e-5);
}

TEST(LearningRateDecayTest, FallsLinearlyToItsFloorAndStaysThere) {
  const LearningRateDecay decay{2e-4, 1000, 0.1};
  EXPECT_DOUBLE_EQ(decay.RateAt(0), 2e-4);
  EXPECT_NEAR(decay.RateAt(500), 2e-4 * 0.55, 1e-15);  // halfway from 1 to 0.1
  EXPECT_NEAR(decay.RateAt(1000), 2e-5, 1e-15);
  EXPECT_NEAR(decay.RateAt(50000), 2e-5, 1e-15);
  EXPECT_DOUBLE_EQ(decay.RateAt(-5), 2e-4);
  const LearningRateDecay constant{2e-4, 0, 0.1};
  EXPECT_DOUBLE_EQ(constant.RateAt(1'000'000'000), 2e-4);

  torch::Tensor weight = torch::zeros({2}, torch::requires_grad());
  torch::optim::Adam adam({weight}, torch::optim::AdamOptions(1e-3));
  SetLearningRate(adam, decay.RateAt(500));
  EXPECT_DOUBLE_EQ(static_cast<torch::optim::AdamOptions&>(adam.param_groups()[0].options()).lr(), decay.RateAt(500));
}

TEST(KlAdaptiveLearningRateTest, KlEstimateIsHandComputedAndNeverNegative) {
  // (r - 1) - log r for log r = log 1.5, log 0.5, 0: 0.5 - 0.405465 = 0.094535,
  // -0.5 + 0.693147 = 0.193147, 0; mean 0.095894. Per sample it is never negative, where
  // old - new is -0.405 for the first.
  const torch::Tensor old_log_probs = torch::zeros({3});
  const torch::Tensor log_probs = torch::tensor({std::log(1.5f), std::log(0.5f), 0.f});
  EXPECT_NEAR(EstimateKl(log_probs, old_log_probs).item<double>(), (0.094535 + 0.193147) / 3, 1e-5);
  EXPECT_NEAR(EstimateKl(old_log_probs, old_log_probs).item<double>(), 0.0, 1e-9);
  const torch::Tensor random = torch::randn({64});
  EXPECT_GE(EstimateKl(random, torch::randn({64})).item<double>(), 0.0);
}

TEST(AmpLossTest, LeastSquaresHandComputed) {
  // expert d = [1, 0, 2]: (d - 1)^2 = [0, 1, 1], 0.5 * mean = 1/3
  // policy d = [-1, 1]:   (d + 1)^2 = [0, 4],    0.5 * mean = 1
  // gp = 0.5, w = 5: total = 1/3 + 1 + 2.5 = 3.833333
  const torch::Tensor expert = T({1, 0, 2}).requires_grad_(true);
  const torch::Tensor policy = T({-1, 1}).requires_grad_(true);
  const torch::Tensor gp = torch::tensor(0.5f).requires_grad_(true);
  const AmpLossTerms terms = ComputeAmpLoss(expert, policy, gp, 5.0);
  EXPECT_NEAR(terms.expert_loss.item<double>(), 1.0 / 3.0, 1e-6);
  EXPECT_NEAR(terms.policy_loss.item<double>(), 1.0, 1e-6);
  EXPECT_NEAR(terms.gradient_penalty.item<double>(), 0.5, 1e-6);
  EXPECT_NEAR(terms.total.item<double>(), 1.0 / 3.0 + 1.0 + 2.5, 1e-5);
  EXPECT_NEAR(terms.expert_logit_mean.item<double>(), 1.0, 1e-6);
  EXPECT_NEAR(terms.policy_logit_mean.item<double>(), 0.0, 1e-6);
  EXPECT_FALSE(terms.expert_logit_mean.requires_grad());

  // d total / d d_e = (d_e - 1) / 3 = [0, -1/3, 1/3]; d / d d_p = (d_p + 1) / 2 = [0, 1];
  // d total / d gp = w = 5.
  terms.total.backward();
  ExpectTensorNear(expert.grad(), T({0.0f, -1.0f / 3.0f, 1.0f / 3.0f}));
  ExpectTensorNear(policy.grad(), T({0.0f, 1.0f}));
  EXPECT_NEAR(gp.grad().item<double>(), 5.0, 1e-6);

  // Without a gradient penalty: total = 4/3.
  EXPECT_NEAR(ComputeAmpLoss(expert, policy, torch::Tensor(), 5.0).total.item<double>(),
              4.0 / 3.0, 1e-5);
}

TEST(AmpLossTest, Reward) {
  // 1 - 0.25 (d - 1)^2: d=1 -> 1; d=-1 -> 0; d=3 -> 0; d=0 -> 0.75; d=2 -> 0.75;
  // d=-3 -> 1 - 4 = -3, clamped to 0.
  const torch::Tensor logits = torch::tensor({{1.0f}, {-1.0f}, {3.0f}, {0.0f}, {2.0f}, {-3.0f}})
                                   .requires_grad_(true);
  const torch::Tensor reward = AmpReward(logits);
  ExpectTensorNear(reward, torch::tensor({{1.0f}, {0.0f}, {0.0f}, {0.75f}, {0.75f}, {0.0f}}));
  EXPECT_FALSE(reward.requires_grad());
}

// ------------------------------------------------------------------------------------------
// CRC32C

TEST(TerminationCurriculumTest, TightensWhileEpisodesReachTheEndAndLoosensWhenTheyDoNot) {
  TerminationCurriculum curriculum(1.0, 0.2);
  EXPECT_DOUBLE_EQ(curriculum.distance(), 1.0);
  const double step = TerminationCurriculum::kStepShare * 0.8;
  curriculum.Update(0.9);
  EXPECT_NEAR(curriculum.distance(), 1.0 - step, 1e-12);
  curriculum.Update(0.3);  // between the thresholds: stays
  EXPECT_NEAR(curriculum.distance(), 1.0 - step, 1e-12);
  curriculum.Update(0.1);
  EXPECT_NEAR(curriculum.distance(), 1.0, 1e-12);
  curriculum.Update(0.0);  // never looser than start
  EXPECT_DOUBLE_EQ(curriculum.distance(), 1.0);
  for (int i = 0; i < 100; ++i) curriculum.Update(1.0);  // never tighter than end
  EXPECT_DOUBLE_EQ(curriculum.distance(), 0.2);
  curriculum.set_distance(5.0);
  EXPECT_DOUBLE_EQ(curriculum.distance(), 1.0);
  TerminationCurriculum fixed(0.25, 0.25);
  fixed.Update(1.0);
  fixed.Update(0.0);
  EXPECT_DOUBLE_EQ(fixed.distance(), 0.25);
}

TEST(Crc32cTest, KnownVectors) {
  EXPECT_EQ(Crc32c(""), 0x00000000u);
  EXPECT_EQ(Crc32c("123456789"), 0xE3069283u);
  // RFC 3720 (iSCSI) B.4.
  EXPECT_EQ(Crc32c(std::string(32, '\0')), 0x8A9136AAu);
  EXPECT_EQ(Crc32c(std::string(32, '\xff')), 0x62A8AB43u);
  std::string ascending(32, '\0');
  for (int i = 0; i < 32; ++i) ascending[i] = static_cast<char>(i);
  EXPECT_EQ(Crc32c(ascending), 0x46DD794Eu);

  const uint32_t crc = 0xE3069283u;
  EXPECT_EQ(MaskCrc32c(crc), ((crc >> 15) | (crc << 17)) + 0xa282ead8u);
}

// ------------------------------------------------------------------------------------------
// TensorBoard event file, parsed back with an independent minimal protobuf reader.

uint64_t ReadLittleEndian(absl::string_view bytes) {
  uint64_t value = 0;
  for (size_t i = 0; i < bytes.size(); ++i) {
    value |= static_cast<uint64_t>(static_cast<unsigned char>(bytes[i])) << (8 * i);
  }
  return value;
}

struct ProtoField {
  uint32_t number = 0;
  uint32_t wire_type = 0;
  uint64_t varint = 0;   // wire type 0
  std::string bytes;     // wire types 1, 2, 5 (raw)
};

bool ReadVarint(absl::string_view* in, uint64_t* value) {
  *value = 0;
  for (int shift = 0; shift < 64 && !in->empty(); shift += 7) {
    const auto byte = static_cast<unsigned char>(in->front());
    in->remove_prefix(1);
    *value |= static_cast<uint64_t>(byte & 0x7F) << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

std::vector<ProtoField> ParseProto(absl::string_view in) {
  std::vector<ProtoField> fields;
  while (!in.empty()) {
    ProtoField field;
    uint64_t key;
    if (!ReadVarint(&in, &key)) ADD_FAILURE() << "truncated key";
    field.number = static_cast<uint32_t>(key >> 3);
    field.wire_type = static_cast<uint32_t>(key & 7);
    size_t size = 0;
    switch (field.wire_type) {
      case 0:
        if (!ReadVarint(&in, &field.varint)) ADD_FAILURE() << "truncated varint";
        fields.push_back(field);
        continue;
      case 1: size = 8; break;
      case 5: size = 4; break;
      case 2: {
        uint64_t length;
        if (!ReadVarint(&in, &length)) ADD_FAILURE() << "truncated length";
        size = length;
        break;
      }
      default:
        ADD_FAILURE() << "unexpected wire type " << field.wire_type;
        return fields;
    }
    if (size > in.size()) {
      ADD_FAILURE() << "field " << field.number << " overruns the message";
      return fields;
    }
    field.bytes = std::string(in.substr(0, size));
    in.remove_prefix(size);
    fields.push_back(field);
  }
  return fields;
}

struct DecodedEvent {
  double wall_time = 0;
  int64_t step = 0;
  std::string file_version;
  std::vector<std::pair<std::string, float>> values;  // tag, simple_value
};

DecodedEvent DecodeEvent(absl::string_view payload) {
  DecodedEvent event;
  for (const ProtoField& field : ParseProto(payload)) {
    if (field.number == 1) {
      EXPECT_EQ(field.wire_type, 1u);
      const uint64_t bits = ReadLittleEndian(field.bytes);
      std::memcpy(&event.wall_time, &bits, 8);
    } else if (field.number == 2) {
      EXPECT_EQ(field.wire_type, 0u);
      event.step = static_cast<int64_t>(field.varint);
    } else if (field.number == 3) {
      EXPECT_EQ(field.wire_type, 2u);
      event.file_version = field.bytes;
    } else if (field.number == 5) {
      EXPECT_EQ(field.wire_type, 2u);
      for (const ProtoField& value : ParseProto(field.bytes)) {  // Summary
        EXPECT_EQ(value.number, 1u);
        EXPECT_EQ(value.wire_type, 2u);
        std::pair<std::string, float> tag_value;
        for (const ProtoField& part : ParseProto(value.bytes)) {  // Summary.Value
          if (part.number == 1) {
            EXPECT_EQ(part.wire_type, 2u);
            tag_value.first = part.bytes;
          } else if (part.number == 2) {
            EXPECT_EQ(part.wire_type, 5u);
            const auto bits = static_cast<uint32_t>(ReadLittleEndian(part.bytes));
            std::memcpy(&tag_value.second, &bits, 4);
          } else {
            ADD_FAILURE() << "unexpected Summary.Value field " << part.number;
          }
        }
        event.values.push_back(tag_value);
      }
    } else {
      ADD_FAILURE() << "unexpected Event field " << field.number;
    }
  }
  return event;
}

// Splits a TFRecord file, checking every length and both masked CRC32Cs.
std::vector<std::string> ReadRecords(absl::string_view file) {
  std::vector<std::string> payloads;
  while (!file.empty()) {
    if (file.size() < 12) {
      ADD_FAILURE() << "truncated record header";
      break;
    }
    const absl::string_view length_bytes = file.substr(0, 8);
    const uint64_t length = ReadLittleEndian(length_bytes);
    EXPECT_EQ(ReadLittleEndian(file.substr(8, 4)), MaskCrc32c(Crc32c(length_bytes)))
        << "length CRC of record " << payloads.size();
    file.remove_prefix(12);
    if (file.size() < length + 4) {
      ADD_FAILURE() << "record " << payloads.size() << " of " << length << " bytes is truncated";
      break;
    }
    const absl::string_view payload = file.substr(0, length);
    EXPECT_EQ(ReadLittleEndian(file.substr(length, 4)), MaskCrc32c(Crc32c(payload)))
        << "payload CRC of record " << payloads.size();
    payloads.emplace_back(payload);
    file.remove_prefix(length + 4);
  }
  return payloads;
}

TEST_F(TensorBoardWriterTest, RoundTrip) {
  const std::filesystem::path dir = dir_ / "run";  // created by Open
  // Wall times come from the system clock; time() is a coarse clock a few ms behind it.
  const auto now = [] {
    return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  const double before = now();
  auto writer = TensorBoardWriter::Open(dir.string());
  ASSERT_TRUE(writer.ok()) << writer.status();
  const std::string path = (*writer)->path();
  EXPECT_EQ(std::filesystem::path(path).parent_path(), dir);
  EXPECT_THAT(std::filesystem::path(path).filename().string(),
              ::testing::StartsWith("events.out.tfevents."));

  ASSERT_TRUE((*writer)->AddScalar("loss/policy", 0, 0.5).ok());
  ASSERT_TRUE((*writer)->AddScalar("loss/value", 300, -1.25).ok());
  ASSERT_TRUE((*writer)->AddScalar("reward/amp", int64_t{123456789012}, 3.0).ok());
  ASSERT_TRUE((*writer)->Flush().ok());

  const std::vector<std::string> records = ReadRecords(ReadFile(path));
  ASSERT_EQ(records.size(), 4u);

  const DecodedEvent header = DecodeEvent(records[0]);
  EXPECT_EQ(header.file_version, "brain.Event:2");
  EXPECT_GE(header.wall_time, before - 1);
  EXPECT_LE(header.wall_time, now() + 1.0);
  EXPECT_TRUE(header.values.empty());

  const struct {
    const char* tag;
    int64_t step;
    float value;
  } expected[] = {{"loss/policy", 0, 0.5f}, {"loss/value", 300, -1.25f},
                  {"reward/amp", 123456789012, 3.0f}};
  for (int i = 0; i < 3; ++i) {
    const DecodedEvent event = DecodeEvent(records[i + 1]);
    EXPECT_EQ(event.step, expected[i].step);
    EXPECT_GE(event.wall_time, before - 1);
    EXPECT_TRUE(event.file_version.empty());
    ASSERT_EQ(event.values.size(), 1u);
    EXPECT_EQ(event.values[0].first, expected[i].tag);
    EXPECT_EQ(event.values[0].second, expected[i].value);
  }

  // A second writer in the same second gets its own file.
  auto second = TensorBoardWriter::Open(dir.string());
  ASSERT_TRUE(second.ok()) << second.status();
  EXPECT_NE((*second)->path(), path);
}

TEST_F(TensorBoardWriterTest, UnwritableDirectoryNamesThePath) {
  // A regular file where the run directory's parent should be: fails even as root.
  const std::filesystem::path blocker = dir_ / "blocker";
  std::ofstream(blocker) << "not a directory";
  const std::string run_dir = (blocker / "run").string();
  auto writer = TensorBoardWriter::Open(run_dir);
  ASSERT_FALSE(writer.ok());
  EXPECT_THAT(writer.status().message(), HasSubstr(run_dir));

  const std::string csv = (blocker / "log.csv").string();
  auto logger = CsvLogger::Open(csv, {"step"});
  ASSERT_FALSE(logger.ok());
  EXPECT_THAT(logger.status().message(), HasSubstr(csv));
}

// ------------------------------------------------------------------------------------------
// CSV

TEST_F(CsvLoggerTest, HeaderAppendAndResume) {
  const std::string path = (dir_ / "progress.csv").string();
  {
    auto logger = CsvLogger::Open(path, {"step", "loss"});
    ASSERT_TRUE(logger.ok()) << logger.status();
    ASSERT_TRUE((*logger)->Append({1, 0.5}).ok());
    ASSERT_TRUE((*logger)->Append({2, 0.1}).ok());
    // Flushed per row: readable before the logger closes.
    EXPECT_EQ(ReadFile(path), "step,loss\n1,0.5\n2,0.1\n");
    const absl::Status wrong = (*logger)->Append({3});
    EXPECT_EQ(wrong.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(wrong.message(), HasSubstr(path));
  }
  {
    // Resumed run, same header: no second header.
    auto logger = CsvLogger::Open(path, {"step", "loss"});
    ASSERT_TRUE(logger.ok()) << logger.status();
    ASSERT_TRUE((*logger)->Append({3, -1}).ok());
    ASSERT_TRUE((*logger)->Append({1234567, 1e-9}).ok());
  }
  EXPECT_EQ(ReadFile(path), "step,loss\n1,0.5\n2,0.1\n3,-1\n1234567,1e-09\n");

  auto mismatched = CsvLogger::Open(path, {"step", "kl"});
  ASSERT_FALSE(mismatched.ok());
  EXPECT_EQ(mismatched.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(mismatched.status().message(), HasSubstr(path));
  EXPECT_THAT(mismatched.status().message(), HasSubstr("step,kl"));
  EXPECT_FALSE(CsvLogger::Open(path, {"step"}).ok()) << "fewer columns than the file is not a resume";
  EXPECT_EQ(ReadFile(path), "step,loss\n1,0.5\n2,0.1\n3,-1\n1234567,1e-09\n");  // untouched

  EXPECT_FALSE(CsvLogger::Open(path, {}).ok());
  EXPECT_FALSE(CsvLogger::Open(path, {"a,b"}).ok());
}

TEST_F(CsvLoggerTest, FreshStartReplacesAnOldRunsRows) {
  // Without --resume the learner starts a new run in a used run directory: its curve must not
  // continue the old run's rows, whatever their header.
  const std::string path = (dir_ / "progress.csv").string();
  {
    auto old_run = CsvLogger::Open(path, {"step", "loss"});
    ASSERT_TRUE(old_run.ok()) << old_run.status();
    ASSERT_TRUE((*old_run)->Append({1, 0.5}).ok());
  }
  {
    auto fresh = CsvLogger::Open(path, {"step", "loss"}, CsvLogger::Start::kFresh);
    ASSERT_TRUE(fresh.ok()) << fresh.status();
    ASSERT_TRUE((*fresh)->Append({1, 0.25}).ok());
  }
  EXPECT_EQ(ReadFile(path), "step,loss\n1,0.25\n");
  auto other_header = CsvLogger::Open(path, {"step", "kl"}, CsvLogger::Start::kFresh);
  ASSERT_TRUE(other_header.ok()) << other_header.status();
  EXPECT_EQ(ReadFile(path), "step,kl\n");
}

TEST_F(CsvLoggerTest, TextCellsAreWrittenAsGivenAndSeparatorsRefused) {
  // The family trainer's rows carry its curriculum mode as text and its own precisions.
  const std::string path = (dir_ / "progress.csv").string();
  auto logger = CsvLogger::Open(path, {"iteration", "curriculum_mode", "coverage"});
  ASSERT_TRUE(logger.ok()) << logger.status();
  ASSERT_TRUE((*logger)->AppendCells({"1", "exploration", "0.2500"}).ok());
  const absl::Status comma = (*logger)->AppendCells({"2", "a,b", "0.5"});
  EXPECT_EQ(comma.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(comma.message()), ::testing::HasSubstr("curriculum_mode"));
  EXPECT_FALSE((*logger)->AppendCells({"2", "refinement"}).ok()) << "one cell short";
  EXPECT_EQ(ReadFile(path), "iteration,curriculum_mode,coverage\n1,exploration,0.2500\n");
}

TEST_F(CsvLoggerTest, ResumeUnderMoreColumnsPadsTheOldRows) {
  // A run from an older version, resumed by one that logs more columns at the end.
  const std::string path = (dir_ / "progress.csv").string();
  std::ofstream(path) << "step,loss\n1,0.5\n2,0.1\n";
  {
    auto logger = CsvLogger::Open(path, {"step", "loss", "kl", "lag"});
    ASSERT_TRUE(logger.ok()) << logger.status();
    ASSERT_TRUE((*logger)->Append({3, 0.25, 0.01, 1}).ok());
  }
  EXPECT_EQ(ReadFile(path), "step,loss,kl,lag\n1,0.5,,\n2,0.1,,\n3,0.25,0.01,1\n");
  // "ste" is a prefix of the header's text, not of its columns.
  std::ofstream(path) << "ste\n1\n";
  EXPECT_FALSE(CsvLogger::Open(path, {"step", "loss"}).ok());
}

TEST_F(CsvLoggerTest, ResumeAfterTornRowStartsANewLine) {
  const std::string path = (dir_ / "progress.csv").string();
  std::ofstream(path) << "step,loss\n1,0.";
  {
    auto logger = CsvLogger::Open(path, {"step", "loss"});
    ASSERT_TRUE(logger.ok()) << logger.status();
    ASSERT_TRUE((*logger)->Append({2, 3}).ok());
  }
  EXPECT_EQ(ReadFile(path), "step,loss\n1,0.\n2,3\n");
}

}  // namespace
}  // namespace modskill::learner
