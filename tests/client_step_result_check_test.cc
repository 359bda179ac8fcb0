// The learner reads step results straight from their bytes: a result whose tensors do not match
// the session (dtype, rows, width, byte count) is refused by the client, naming the field.
#include <string>

#include <gmock/gmock.h>

#include "client/cpp/step_result_check.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

constexpr int kEnvs = 3;

void SetTensor(v1::Tensor* tensor, v1::DType dtype, std::vector<int64_t> shape, int item_size) {
  tensor->set_dtype(dtype);
  int64_t elements = 1;
  for (int64_t d : shape) {
    tensor->add_shape(d);
    elements *= d;
  }
  tensor->set_data(std::string(static_cast<size_t>(elements * item_size), '\0'));
}

v1::EnvSpec Spec() {
  v1::EnvSpec spec;
  spec.set_obs_size(5);
  spec.set_amp_obs_per_frame(4);
  spec.add_reward_terms("pos");
  spec.add_reward_terms("energy");
  spec.add_parts()->set_name("a");
  spec.add_parts()->set_name("b");
  return spec;
}

v1::StepResult Valid() {
  v1::StepResult result;
  SetTensor(result.mutable_obs(), v1::FLOAT32, {kEnvs, 5}, 4);
  SetTensor(result.mutable_amp_obs(), v1::FLOAT32, {kEnvs, 8}, 4);
  SetTensor(result.mutable_reward(), v1::FLOAT32, {kEnvs}, 4);
  SetTensor(result.mutable_reward_terms(), v1::FLOAT32, {kEnvs, 2}, 4);
  SetTensor(result.mutable_done(), v1::UINT8, {kEnvs}, 1);
  SetTensor(result.mutable_truncated(), v1::UINT8, {kEnvs}, 1);
  for (v1::Tensor* t : {result.mutable_clip_id(), result.mutable_frame(), result.mutable_ended_clip_id(),
                        result.mutable_ended_frame()}) {
    SetTensor(t, v1::INT32, {kEnvs}, 4);
  }
  SetTensor(result.mutable_max_body_error(), v1::FLOAT32, {kEnvs}, 4);
  SetTensor(result.mutable_mean_body_error(), v1::FLOAT32, {kEnvs}, 4);
  SetTensor(result.mutable_part_error(), v1::FLOAT32, {kEnvs, 2}, 4);
  return result;
}

void ExpectRefused(const v1::StepResult& result, const std::string& field) {
  const absl::Status status = CheckStepResult(result, kEnvs, Spec());
  EXPECT_EQ(status.code(), absl::StatusCode::kDataLoss) << field << ": " << status;
  EXPECT_THAT(std::string(status.message()), HasSubstr(field));
}

TEST(StepResultCheckTest, AWellFormedResultPassesAndOptionalFieldsMayBeAbsent) {
  EXPECT_TRUE(CheckStepResult(Valid(), kEnvs, Spec()).ok());
  v1::StepResult without = Valid();
  without.clear_amp_obs();
  without.clear_part_error();
  EXPECT_TRUE(CheckStepResult(without, kEnvs, Spec()).ok());
}

TEST(StepResultCheckTest, EveryMismatchNamesItsField) {
  v1::StepResult short_obs = Valid();
  short_obs.mutable_obs()->mutable_data()->resize(10);
  ExpectRefused(short_obs, "obs");
  v1::StepResult wide_obs = Valid();
  SetTensor(wide_obs.mutable_obs(), v1::FLOAT32, {kEnvs, 6}, 4);
  ExpectRefused(wide_obs, "obs");
  v1::StepResult rows = Valid();
  SetTensor(rows.mutable_reward(), v1::FLOAT32, {kEnvs + 1}, 4);
  ExpectRefused(rows, "reward");
  v1::StepResult dtype = Valid();
  SetTensor(dtype.mutable_done(), v1::FLOAT32, {kEnvs}, 4);
  ExpectRefused(dtype, "done");
  v1::StepResult clip = Valid();
  clip.mutable_ended_clip_id()->mutable_data()->resize(2);  // the learner memcpy's 4 * n bytes
  ExpectRefused(clip, "ended_clip_id");
  v1::StepResult parts = Valid();
  SetTensor(parts.mutable_part_error(), v1::FLOAT32, {kEnvs, 3}, 4);
  ExpectRefused(parts, "part_error");
  v1::StepResult amp = Valid();
  SetTensor(amp.mutable_amp_obs(), v1::FLOAT32, {kEnvs, 6}, 4);
  ExpectRefused(amp, "amp_obs");
  v1::StepResult terms = Valid();
  SetTensor(terms.mutable_reward_terms(), v1::FLOAT32, {kEnvs, 1}, 4);
  ExpectRefused(terms, "reward_terms");
  v1::StepResult missing = Valid();
  missing.clear_frame();
  ExpectRefused(missing, "frame");
}

}  // namespace
}  // namespace modskill
