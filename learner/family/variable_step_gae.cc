#include "learner/family/variable_step_gae.h"

#include <cmath>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"

namespace modskill::learner::family {
namespace {

std::string Shape(const torch::Tensor& t) {
  std::string out = "[";
  for (int64_t i = 0; i < t.dim(); ++i) absl::StrAppend(&out, i ? ", " : "", t.size(i));
  return out + "]";
}

absl::Status CheckField(const char* name, const torch::Tensor& t, torch::IntArrayRef shape) {
  if (!t.defined()) return absl::InvalidArgumentError(absl::StrCat("variable-step GAE: ", name, " is missing"));
  if (t.sizes() != shape) {
    return absl::InvalidArgumentError(absl::StrCat("variable-step GAE: ", name, " is ", Shape(t), ", expected ",
                                                   Shape(torch::empty(shape))));
  }
  if (!torch::isfinite(t).all().item<bool>()) {
    return absl::InvalidArgumentError(absl::StrCat("variable-step GAE: ", name, " has a non-finite entry"));
  }
  return absl::OkStatus();
}

absl::Status CheckRollout(const VariableStepRollout& r, double gamma, double lambda) {
  if (!(gamma > 0 && gamma < 1)) return absl::InvalidArgumentError(absl::StrCat("variable-step GAE: gamma ", gamma, " outside (0, 1)"));
  if (!(lambda >= 0 && lambda <= 1)) return absl::InvalidArgumentError(absl::StrCat("variable-step GAE: lambda ", lambda, " outside [0, 1]"));
  if (!r.values.defined() || r.values.dim() != 2) {
    return absl::InvalidArgumentError("variable-step GAE: values must be a [T, N] tensor");
  }
  const torch::IntArrayRef tn = r.values.sizes();
  const std::pair<const char*, const torch::Tensor*> fields[] = {
      {"continuous_reward", &r.continuous_reward}, {"spike_reward", &r.spike_reward},
      {"phase_step", &r.phase_step}, {"terminated", &r.terminated}};
  for (const auto& [name, tensor] : fields) {
    if (absl::Status s = CheckField(name, *tensor, tn); !s.ok()) return s;
  }
  if (absl::Status s = CheckField("last_values", r.last_values, {tn[1]}); !s.ok()) return s;
  if (!(r.phase_step > 0).all().item<bool>()) {
    return absl::InvalidArgumentError("variable-step GAE: phase_step has an entry <= 0 (the warp is monotonic)");
  }
  if (r.truncated.defined() != r.timeout_values.defined()) {
    return absl::InvalidArgumentError("variable-step GAE: truncated and timeout_values come together");
  }
  if (r.truncated.defined()) {
    if (absl::Status s = CheckField("truncated", r.truncated, tn); !s.ok()) return s;
    if (absl::Status s = CheckField("timeout_values", r.timeout_values, tn); !s.ok()) return s;
  }
  return absl::OkStatus();
}

}  // namespace

double ContinuousRewardWeight(double gamma, double phase_step) {
  return (std::pow(gamma, phase_step) - 1.0) / (gamma - 1.0);
}

absl::StatusOr<Advantages> ComputeVariableStepGae(const VariableStepRollout& rollout, double gamma,
                                                  double lambda) {
  if (absl::Status s = CheckRollout(rollout, gamma, lambda); !s.ok()) return s;
  torch::NoGradGuard no_grad;
  const auto f64 = [](const torch::Tensor& t) { return t.detach().to(torch::kFloat64); };
  const torch::Tensor r_c = f64(rollout.continuous_reward), r_s = f64(rollout.spike_reward);
  const torch::Tensor dphi = f64(rollout.phase_step), values = f64(rollout.values);
  const torch::Tensor failed = f64(rollout.terminated);
  const torch::Tensor timed_out = rollout.truncated.defined() ? f64(rollout.truncated) : torch::zeros_like(failed);
  const torch::Tensor timeout_values =
      rollout.timeout_values.defined() ? f64(rollout.timeout_values) : torch::zeros_like(values);
  // Per step: gamma^dphi, (gamma lambda)^dphi and the continuous weight w(dphi), [T, N].
  const torch::Tensor discount = torch::pow(gamma, dphi);
  const torch::Tensor trace = torch::pow(gamma * lambda, dphi);
  const torch::Tensor weight = (discount - 1.0) / (gamma - 1.0);
  const torch::Tensor continues = (1.0 - failed) * (1.0 - timed_out);
  const torch::Tensor rewards = weight * r_c + r_s + discount * timeout_values * timed_out;
  torch::Tensor adv = torch::empty_like(values);
  torch::Tensor next_value = f64(rollout.last_values);
  torch::Tensor next_adv = torch::zeros_like(next_value);
  for (int64_t t = values.size(0) - 1; t >= 0; --t) {
    // Eq. 9: delta_t = w r_c + r_s + gamma^dphi V' - V, with V' = 0 past a failure and the
    // time-out's own bootstrap (already in `rewards`) past a time-out.
    const torch::Tensor delta = rewards[t] + discount[t] * next_value * continues[t] - values[t];
    next_adv = delta + trace[t] * continues[t] * next_adv;  // A_t = delta_t + (gamma lambda)^dphi A_{t+1}
    adv[t] = next_adv;
    next_value = values[t];
  }
  const torch::Dtype out = rollout.values.scalar_type();
  return Advantages{adv.to(out), (adv + values).to(out)};
}

}  // namespace modskill::learner::family
