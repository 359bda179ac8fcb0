// ModSkill's skill attention: each body part's observation is mapped to a key, a query and a
// value; scaled dot-product attention across parts mixes the values into one skill embedding
// z_k per part, normalized to the unit sphere.
#ifndef MODSKILL_LEARNER_SKILL_ATTENTION_H_
#define MODSKILL_LEARNER_SKILL_ATTENTION_H_

#include <vector>

#include <torch/torch.h>

#include "learner/model_config.h"
#include "learner/part_controller.h"

namespace modskill::learner {

struct SkillAttentionOutput {
  torch::Tensor z;          // [B, P, E], unit norm along E
  torch::Tensor attention;  // [B, P, P], alpha[b, k, j]: weight of part j's value in z_k; rows sum to 1
};

// Per part p, MLPs key_p, query_p, value_p (registered "key<p>", "query<p>", "value<p>"): part
// p's obs slice -> attention_hidden... -> embed_dim, ELU between hidden layers, linear output.
//   alpha_kj = softmax_j(q_k . key_j / sqrt(E)),  z_k = normalize(sum_j alpha_kj v_j)
// with normalize(z) = z / max(||z||, 1e-6). Without attention (config.attention == false) there
// are no key or query maps: z_k = normalize(v_k), alpha = identity.
class SkillAttentionImpl : public torch::nn::Module {
 public:
  SkillAttentionImpl(const NetworkLayout& layout, const ModelConfig& config);

  // obs: [B, obs_size] (normalized) -> z [B, P, E], attention [B, P, P]
  SkillAttentionOutput forward(const torch::Tensor& obs);

  const NetworkLayout& layout() const { return layout_; }
  int64_t embed_dim() const { return embed_dim_; }
  bool uses_attention() const { return attention_; }
  // Per part; keys() and queries() are empty without attention.
  const std::vector<Mlp>& keys() const { return keys_; }
  const std::vector<Mlp>& queries() const { return queries_; }
  const std::vector<Mlp>& values() const { return values_; }

  // z / max(||z||, 1e-6) along the last dim.
  static torch::Tensor NormalizeToSphere(const torch::Tensor& z);
  static constexpr double kMinNorm = 1e-6;

 private:
  NetworkLayout layout_;
  int64_t embed_dim_;
  bool attention_;
  std::vector<Mlp> keys_, queries_, values_;
};
TORCH_MODULE(SkillAttention);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_SKILL_ATTENTION_H_
