#include "learner/wire_torch.h"

#include "absl/strings/str_cat.h"
#include "common/wire/tensor_codec.h"

namespace modskill::learner {

absl::StatusOr<torch::Tensor> WireToTorch(const v1::Tensor& tensor, absl::string_view field, v1::DType dtype,
                                          const std::vector<int64_t>& shape) {
  if (absl::Status status = AsDataLoss(CheckTensor(tensor, field, dtype, shape)); !status.ok()) return status;
  void* data = const_cast<char*>(tensor.data().data());
  switch (dtype) {
    case v1::FLOAT32:
      return torch::from_blob(data, shape, torch::kFloat32).clone();
    case v1::UINT8:
      return torch::from_blob(data, shape, torch::kUInt8).to(torch::kFloat32);
    case v1::INT32:
      return torch::from_blob(data, shape, torch::kInt32).clone();
    default:
      return absl::InvalidArgumentError(absl::StrCat(field, ": dtype ", v1::DType_Name(dtype), " has no torch type"));
  }
}

}  // namespace modskill::learner
