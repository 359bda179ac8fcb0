// The wire's Tensor (raw little-endian bytes with a shape and a dtype) to and from memory: the
// one place that encodes and decodes it for the server, the C++ client and the learner (the
// learner's torch adapter, learner/wire_torch.h, and Python's numpy one, modskill/tensors.py,
// build on the same checks). Every read checks the dtype, the shape and the byte count first.
#ifndef MODSKILL_COMMON_WIRE_TENSOR_CODEC_H_
#define MODSKILL_COMMON_WIRE_TENSOR_CODEC_H_

#include <cstdint>
#include <initializer_list>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "absl/types/span.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

// A dimension of an expected shape that may take any size up to kMaxTensorDimension.
inline constexpr int64_t kAnySize = -1;
inline constexpr int64_t kMaxTensorDimension = int64_t{1} << 24;

// Bytes per element; 0 for a dtype this build does not know.
int64_t DTypeSize(v1::DType dtype);

// Writes shape, dtype and bytes, reusing the message's existing storage.
void SetFloatTensor(std::initializer_list<int64_t> shape, const float* data, v1::Tensor* tensor);
void SetInt32Tensor(std::initializer_list<int64_t> shape, const int32_t* data, v1::Tensor* tensor);
void SetUint8Tensor(std::initializer_list<int64_t> shape, const uint8_t* data, v1::Tensor* tensor);

// INVALID_ARGUMENT whose message starts with `field` unless the tensor has `dtype`, `shape`
// (kAnySize matching any dimension in [0, kMaxTensorDimension]) and exactly the bytes that
// shape needs. A caller checking a server's answer rather than a request turns the code into
// DATA_LOSS (AsDataLoss).
absl::Status CheckTensor(const v1::Tensor& tensor, absl::string_view field, v1::DType dtype,
                         absl::Span<const int64_t> shape);
absl::Status AsDataLoss(const absl::Status& status);

// CheckTensor, then copies the elements into `out` (resized).
absl::Status ReadFloatTensor(const v1::Tensor& tensor, absl::string_view field, absl::Span<const int64_t> shape,
                             std::vector<float>* out);
// Any shape of the tensor's own rank (every dimension bounded), for callers that take the shape
// from the tensor.
absl::Status ReadFloatTensor(const v1::Tensor& tensor, absl::string_view field, std::vector<float>* out);
absl::Status ReadInt32Tensor(const v1::Tensor& tensor, absl::string_view field, absl::Span<const int64_t> shape,
                             std::vector<int32_t>* out);

}  // namespace modskill

#endif  // MODSKILL_COMMON_WIRE_TENSOR_CODEC_H_
