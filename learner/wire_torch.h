// The learner's adapter from the wire's Tensor to torch: common/wire/tensor_codec.h's checks
// (dtype, shape, byte count), then one copy, since the message's buffer is reused by the next
// result.
#ifndef MODSKILL_LEARNER_WIRE_TORCH_H_
#define MODSKILL_LEARNER_WIRE_TORCH_H_

#include <cstdint>
#include <vector>

#include <torch/torch.h>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner {

// FLOAT32 and UINT8 tensors come back as float32 (UINT8 flags as 0/1), INT32 as int32. The
// error (DATA_LOSS: a server's answer, not a request) names `field`.
absl::StatusOr<torch::Tensor> WireToTorch(const v1::Tensor& tensor, absl::string_view field, v1::DType dtype,
                                          const std::vector<int64_t>& shape);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_WIRE_TORCH_H_
