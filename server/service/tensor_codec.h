// Batch buffers <-> the wire's Tensor (raw little-endian bytes with shape and dtype).
#ifndef MODSKILL_SERVER_SERVICE_TENSOR_CODEC_H_
#define MODSKILL_SERVER_SERVICE_TENSOR_CODEC_H_

#include <cstdint>
#include <initializer_list>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

// Writes shape, dtype and bytes, reusing the message's existing storage.
void SetFloatTensor(std::initializer_list<int64_t> shape, const float* data, v1::Tensor* tensor);
void SetInt32Tensor(std::initializer_list<int64_t> shape, const int32_t* data, v1::Tensor* tensor);
void SetUint8Tensor(std::initializer_list<int64_t> shape, const uint8_t* data, v1::Tensor* tensor);

// Checks dtype FLOAT32, shape == `shape` and the byte count, then copies into `out` (resized).
// `field` names the tensor in error messages.
absl::Status ReadFloatTensor(const v1::Tensor& tensor, absl::string_view field, std::initializer_list<int64_t> shape,
                             std::vector<float>* out);

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_TENSOR_CODEC_H_
