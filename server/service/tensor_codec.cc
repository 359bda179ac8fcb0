#include "server/service/tensor_codec.h"

#include <cstring>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace modskill {
namespace {

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "the wire format is little-endian");

void SetTensor(std::initializer_list<int64_t> shape, v1::DType dtype, const void* data, size_t bytes,
               v1::Tensor* tensor) {
  tensor->clear_shape();
  for (int64_t d : shape) tensor->add_shape(d);
  tensor->set_dtype(dtype);
  tensor->mutable_data()->assign(static_cast<const char*>(data), bytes);
}

int64_t Elements(std::initializer_list<int64_t> shape) {
  int64_t n = 1;
  for (int64_t d : shape) n *= d;
  return n;
}

}  // namespace

void SetFloatTensor(std::initializer_list<int64_t> shape, const float* data, v1::Tensor* tensor) {
  SetTensor(shape, v1::FLOAT32, data, Elements(shape) * sizeof(float), tensor);
}

void SetInt32Tensor(std::initializer_list<int64_t> shape, const int32_t* data, v1::Tensor* tensor) {
  SetTensor(shape, v1::INT32, data, Elements(shape) * sizeof(int32_t), tensor);
}

void SetUint8Tensor(std::initializer_list<int64_t> shape, const uint8_t* data, v1::Tensor* tensor) {
  SetTensor(shape, v1::UINT8, data, Elements(shape), tensor);
}

absl::Status ReadFloatTensor(const v1::Tensor& tensor, absl::string_view field, std::initializer_list<int64_t> shape,
                             std::vector<float>* out) {
  if (tensor.dtype() != v1::FLOAT32) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".dtype: ", v1::DType_Name(tensor.dtype()), ", expected FLOAT32"));
  }
  const bool shape_matches = tensor.shape_size() == static_cast<int>(shape.size()) &&
                             std::equal(shape.begin(), shape.end(), tensor.shape().begin());
  if (!shape_matches) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".shape: [", absl::StrJoin(tensor.shape(), ", "),
                                                   "], expected [", absl::StrJoin(shape, ", "), "]"));
  }
  const size_t expected = static_cast<size_t>(Elements(shape)) * sizeof(float);
  if (tensor.data().size() != expected) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".data: ", tensor.data().size(), " bytes, shape needs ", expected));
  }
  out->resize(Elements(shape));
  std::memcpy(out->data(), tensor.data().data(), expected);
  return absl::OkStatus();
}

}  // namespace modskill
