#include "client/cpp/step_result_check.h"

#include <cstdint>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace modskill {
namespace {

int64_t ItemSize(v1::DType dtype) {
  switch (dtype) {
    case v1::FLOAT32:
    case v1::INT32:
      return 4;
    case v1::UINT8:
      return 1;
    default:
      return 0;
  }
}

// `width` 0: a vector [num_envs]; -1: a matrix of any width; otherwise [num_envs, width].
absl::Status CheckTensor(const v1::Tensor& tensor, const char* field, v1::DType dtype, int num_envs, int64_t width) {
  auto bad = [&](const std::string& why) {
    return absl::DataLossError(absl::StrCat("step result ", field, ": ", why));
  };
  if (tensor.dtype() != dtype) return bad(absl::StrCat("dtype ", v1::DType_Name(tensor.dtype()), ", expected ", v1::DType_Name(dtype)));
  const int rank = width == 0 ? 1 : 2;
  if (tensor.shape_size() != rank) return bad(absl::StrCat("shape [", absl::StrJoin(tensor.shape(), ", "), "], expected rank ", rank));
  if (tensor.shape(0) != num_envs) return bad(absl::StrCat(tensor.shape(0), " rows for ", num_envs, " envs"));
  if (rank == 2 && width > 0 && tensor.shape(1) != width) return bad(absl::StrCat("width ", tensor.shape(1), ", expected ", width));
  if (rank == 2 && (tensor.shape(1) < 0 || tensor.shape(1) > (int64_t{1} << 24))) return bad("width out of range");
  const int64_t elements = rank == 1 ? num_envs : num_envs * tensor.shape(1);
  const int64_t expected = elements * ItemSize(dtype);
  if (static_cast<int64_t>(tensor.data().size()) != expected) {
    return bad(absl::StrCat(tensor.data().size(), " bytes, its shape needs ", expected));
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status CheckStepResult(const v1::StepResult& result, int num_envs, const v1::EnvSpec& spec) {
  struct Field {
    const v1::Tensor& tensor;
    const char* name;
    v1::DType dtype;
    int64_t width;
  };
  const Field required[] = {
      {result.obs(), "obs", v1::FLOAT32, spec.obs_size()},
      {result.reward(), "reward", v1::FLOAT32, 0},
      {result.reward_terms(), "reward_terms", v1::FLOAT32, spec.reward_terms_size()},
      {result.done(), "done", v1::UINT8, 0},
      {result.truncated(), "truncated", v1::UINT8, 0},
      {result.clip_id(), "clip_id", v1::INT32, 0},
      {result.frame(), "frame", v1::INT32, 0},
      {result.ended_clip_id(), "ended_clip_id", v1::INT32, 0},
      {result.ended_frame(), "ended_frame", v1::INT32, 0},
      {result.max_body_error(), "max_body_error", v1::FLOAT32, 0},
      {result.mean_body_error(), "mean_body_error", v1::FLOAT32, 0},
  };
  for (const Field& field : required) {
    if (absl::Status status = CheckTensor(field.tensor, field.name, field.dtype, num_envs, field.width); !status.ok()) {
      return status;
    }
  }
  if (result.has_amp_obs()) {
    if (absl::Status status = CheckTensor(result.amp_obs(), "amp_obs", v1::FLOAT32, num_envs, -1); !status.ok()) {
      return status;
    }
    const int64_t per_frame = spec.amp_obs_per_frame();
    if (per_frame > 0 && result.amp_obs().shape(1) % per_frame != 0) {
      return absl::DataLossError(absl::StrCat("step result amp_obs: width ", result.amp_obs().shape(1),
                                              " is not a whole number of ", per_frame, "-feature frames"));
    }
  }
  if (result.has_part_error() && result.part_error().shape_size() > 0) {
    if (absl::Status status = CheckTensor(result.part_error(), "part_error", v1::FLOAT32, num_envs, spec.parts_size());
        !status.ok()) {
      return status;
    }
  }
  return absl::OkStatus();
}

}  // namespace modskill
