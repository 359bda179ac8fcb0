#include "common/wire/tensor_codec.h"

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

std::string ShapeText(absl::Span<const int64_t> shape) {
  std::vector<std::string> dims;
  for (int64_t d : shape) dims.push_back(d == kAnySize ? "*" : absl::StrCat(d));
  return absl::StrCat("[", absl::StrJoin(dims, ", "), "]");
}

template <typename T>
absl::Status ReadTensor(const v1::Tensor& tensor, absl::string_view field, v1::DType dtype,
                        absl::Span<const int64_t> shape, std::vector<T>* out) {
  if (absl::Status status = CheckTensor(tensor, field, dtype, shape); !status.ok()) return status;
  out->resize(tensor.data().size() / sizeof(T));
  std::memcpy(out->data(), tensor.data().data(), tensor.data().size());
  return absl::OkStatus();
}

}  // namespace

int64_t DTypeSize(v1::DType dtype) {
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

void SetFloatTensor(std::initializer_list<int64_t> shape, const float* data, v1::Tensor* tensor) {
  SetTensor(shape, v1::FLOAT32, data, Elements(shape) * sizeof(float), tensor);
}

void SetInt32Tensor(std::initializer_list<int64_t> shape, const int32_t* data, v1::Tensor* tensor) {
  SetTensor(shape, v1::INT32, data, Elements(shape) * sizeof(int32_t), tensor);
}

void SetUint8Tensor(std::initializer_list<int64_t> shape, const uint8_t* data, v1::Tensor* tensor) {
  SetTensor(shape, v1::UINT8, data, Elements(shape), tensor);
}

absl::Status CheckTensor(const v1::Tensor& tensor, absl::string_view field, v1::DType dtype,
                         absl::Span<const int64_t> shape) {
  if (tensor.dtype() != dtype) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".dtype: ", v1::DType_Name(tensor.dtype()), ", expected ",
                                                   v1::DType_Name(dtype)));
  }
  bool shape_matches = tensor.shape_size() == static_cast<int>(shape.size());
  for (int i = 0; shape_matches && i < tensor.shape_size(); ++i) {
    const int64_t d = tensor.shape(i);
    shape_matches = shape[i] == kAnySize ? d >= 0 && d <= kMaxTensorDimension : d == shape[i];
  }
  if (!shape_matches) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".shape: [", absl::StrJoin(tensor.shape(), ", "),
                                                   "], expected ", ShapeText(shape)));
  }
  // Every dimension is bounded now, but a product of several may still overflow: multiply in
  // doubles first.
  double elements = 1;
  for (int64_t d : tensor.shape()) elements *= static_cast<double>(d);
  const double expected = elements * static_cast<double>(DTypeSize(dtype));
  if (static_cast<double>(tensor.data().size()) != expected) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".data: ", tensor.data().size(), " bytes, shape needs ", expected));
  }
  return absl::OkStatus();
}

absl::Status AsDataLoss(const absl::Status& status) {
  return status.ok() ? status : absl::DataLossError(status.message());
}

absl::Status ReadFloatTensor(const v1::Tensor& tensor, absl::string_view field, absl::Span<const int64_t> shape,
                             std::vector<float>* out) {
  return ReadTensor(tensor, field, v1::FLOAT32, shape, out);
}

absl::Status ReadFloatTensor(const v1::Tensor& tensor, absl::string_view field, std::vector<float>* out) {
  const std::vector<int64_t> any_shape(tensor.shape_size(), kAnySize);
  return ReadTensor(tensor, field, v1::FLOAT32, any_shape, out);
}

absl::Status ReadInt32Tensor(const v1::Tensor& tensor, absl::string_view field, absl::Span<const int64_t> shape,
                             std::vector<int32_t>* out) {
  return ReadTensor(tensor, field, v1::INT32, shape, out);
}

}  // namespace modskill
