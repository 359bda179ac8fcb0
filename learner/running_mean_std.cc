#include "learner/running_mean_std.h"

namespace modskill::learner {

RunningMeanStdImpl::RunningMeanStdImpl(int64_t size) : size_(size) {
  const auto options = torch::TensorOptions().dtype(torch::kFloat64);
  mean_ = register_buffer("mean", torch::zeros({size}, options));
  var_ = register_buffer("var", torch::ones({size}, options));
  count_ = register_buffer("count", torch::zeros({}, options));
}

void RunningMeanStdImpl::Update(const torch::Tensor& batch) {
  TORCH_CHECK(batch.dim() == 2 && batch.size(1) == size_, "RunningMeanStd::Update: expected [B, ", size_,
              "], got ", batch.sizes());
  if (batch.size(0) == 0) return;
  Merge(BatchMoments(batch));
}

RunningMeanStdImpl::Moments RunningMeanStdImpl::BatchMoments(const torch::Tensor& batch) const {
  TORCH_CHECK(batch.dim() == 2 && batch.size(1) == size_ && batch.size(0) > 0,
              "RunningMeanStd::BatchMoments: expected [B > 0, ", size_, "], got ", batch.sizes());
  torch::NoGradGuard no_grad;
  // The batch's own moments in its own precision (a float64 copy of a [10k, 2320] float32 AMP
  // batch cost 0.5 s per iteration), merged into the float64 running moments.
  const torch::Tensor x = batch.scalar_type() == torch::kFloat64 ? batch.detach() : batch.detach().to(torch::kFloat32);
  return Moments{static_cast<double>(x.size(0)), x.mean(0).to(torch::kFloat64),
                 x.var(0, /*unbiased=*/false).to(torch::kFloat64)};
}

// Chan et al.: delta = mean_b - mean_a; mean = mean_a + delta n_b / n;
// M2 = M2_a + M2_b + delta^2 n_a n_b / n; var = M2 / n.
void RunningMeanStdImpl::Merge(const Moments& batch) {
  if (batch.count == 0) return;
  torch::NoGradGuard no_grad;
  const double n_a = count_.item<double>(), n_b = batch.count;
  const double n = n_a + n_b;
  const torch::Tensor delta = batch.mean - mean_;
  const torch::Tensor m2 = var_ * n_a + batch.var * n_b + delta.square() * (n_a * n_b / n);
  if (frozen_.defined()) {
    mean_.copy_(torch::where(frozen_, mean_, mean_ + delta * (n_b / n)));
    var_.copy_(torch::where(frozen_, var_, m2 / n));
  } else {
    mean_.add_(delta * (n_b / n));
    var_.copy_(m2 / n);
  }
  count_.fill_(n);
}

RunningMeanStdImpl::Moments RunningMeanStdImpl::Combine(const Moments& a, const Moments& b) {
  if (b.count == 0) return a;
  if (a.count == 0) return b;
  const double n = a.count + b.count;
  const torch::Tensor delta = b.mean - a.mean;
  const torch::Tensor m2 = a.var * a.count + b.var * b.count + delta.square() * (a.count * b.count / n);
  return Moments{n, a.mean + delta * (b.count / n), m2 / n};
}

void RunningMeanStdImpl::FreezeDims(const torch::Tensor& mask) {
  TORCH_CHECK(mask.dim() == 1 && mask.size(0) == size_ && mask.scalar_type() == torch::kBool,
              "RunningMeanStd::FreezeDims: expected a bool mask [", size_, "], got ", mask.sizes());
  frozen_ = mask.clone();
}

torch::Tensor RunningMeanStdImpl::Normalize(const torch::Tensor& x) const {
  const torch::Tensor mean = mean_.to(x.scalar_type());
  const torch::Tensor std = torch::sqrt(var_ + kEpsilon).to(x.scalar_type());
  return torch::clamp((x - mean) / std, -kClip, kClip);
}

}  // namespace modskill::learner
