#include "learner/skill_attention.h"

#include <cmath>
#include <string>

namespace modskill::learner {

SkillAttentionImpl::SkillAttentionImpl(const NetworkLayout& layout, const ModelConfig& config)
    : layout_(layout), embed_dim_(config.embed_dim), attention_(config.attention) {
  const absl::Status valid = layout.Validate();
  TORCH_CHECK(valid.ok(), "SkillAttention: ", valid.ToString());
  TORCH_CHECK(embed_dim_ > 0, "SkillAttention: embed_dim is ", embed_dim_);
  for (size_t p = 0; p < layout.parts.size(); ++p) {
    const int64_t in = layout.parts[p].obs_size;
    const std::string index = std::to_string(p);
    if (attention_) {
      keys_.push_back(register_module("key" + index, Mlp(in, config.attention_hidden, embed_dim_, Activation::kElu)));
      queries_.push_back(
          register_module("query" + index, Mlp(in, config.attention_hidden, embed_dim_, Activation::kElu)));
    }
    values_.push_back(register_module("value" + index, Mlp(in, config.attention_hidden, embed_dim_, Activation::kElu)));
  }
}

torch::Tensor SkillAttentionImpl::NormalizeToSphere(const torch::Tensor& z) {
  return z / torch::clamp_min(torch::sqrt(torch::sum(z * z, {-1}, /*keepdim=*/true)), kMinNorm);
}

SkillAttentionOutput SkillAttentionImpl::forward(const torch::Tensor& obs) {
  TORCH_CHECK(obs.dim() == 2 && obs.size(1) == layout_.obs_size, "SkillAttention: expected obs [B, ",
              layout_.obs_size, "], got ", obs.sizes());
  const int64_t num_parts = static_cast<int64_t>(layout_.parts.size());
  std::vector<torch::Tensor> keys, queries, values;
  for (int64_t p = 0; p < num_parts; ++p) {
    const PartSlices& part = layout_.parts[p];
    const torch::Tensor part_obs = obs.slice(1, part.obs_start, part.obs_start + part.obs_size);  // [B, O_p]
    values.push_back(values_[p]->forward(part_obs));                                              // [B, E]
    if (attention_) {
      keys.push_back(keys_[p]->forward(part_obs));
      queries.push_back(queries_[p]->forward(part_obs));
    }
  }
  const torch::Tensor v = torch::stack(values, 1);  // [B, P, E]
  SkillAttentionOutput out;
  if (attention_) {
    const torch::Tensor q = torch::stack(queries, 1);  // [B, P, E]
    const torch::Tensor k = torch::stack(keys, 1);     // [B, P, E]
    const torch::Tensor scores = torch::matmul(q, k.transpose(1, 2)) / std::sqrt(static_cast<double>(embed_dim_));
    out.attention = torch::softmax(scores, -1);                        // [B, P, P]
    out.z = NormalizeToSphere(torch::matmul(out.attention, v));        // [B, P, E]
  } else {
    out.attention = torch::eye(num_parts, v.options()).expand({obs.size(0), num_parts, num_parts});
    out.z = NormalizeToSphere(v);
  }
  return out;
}

}  // namespace modskill::learner
