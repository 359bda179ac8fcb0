#include "common/policy/policy_checkpoint.h"

#include <dlfcn.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include <ATen/Parallel.h>
#include <torch/script.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"

namespace modskill {

absl::StatusOr<std::string> AffinePolicyBytes(const PolicySpec& spec, const std::vector<float>& weight,
                                              const std::vector<float>& bias) {
  const int64_t obs = spec.obs_size, act = spec.action_size;
  if (!weight.empty() && weight.size() != static_cast<size_t>(obs * act)) {
    return absl::InvalidArgumentError(absl::StrCat("weight: ", weight.size(), " values, expected ", obs * act));
  }
  if (!bias.empty() && bias.size() != static_cast<size_t>(act)) {
    return absl::InvalidArgumentError(absl::StrCat("bias: ", bias.size(), " values, expected ", act));
  }
  try {
    torch::jit::Module module("AffinePolicy");
    torch::Tensor w = weight.empty() ? torch::zeros({act, obs}) : torch::tensor(weight).reshape({act, obs});
    torch::Tensor b = bias.empty() ? torch::zeros({act}) : torch::tensor(bias);
    module.register_parameter("weight", w, /*is_buffer=*/false);
    module.register_parameter("bias", b, /*is_buffer=*/false);
    module.define(R"(
def forward(self, obs):
    return torch.clamp(torch.addmm(self.bias, obs, self.weight.t()), -1.0, 1.0)
)");
    std::ostringstream out(std::ios::binary);
    module.save(out, {{kCheckpointSpecFile, spec.ToJson()}});
    return out.str();
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("AffinePolicyBytes: ", message.substr(0, message.find('\n'))));
  }
}

absl::Status SaveAffinePolicy(const std::string& path, const PolicySpec& spec, const std::vector<float>& weight,
                              const std::vector<float>& bias) {
  auto bytes = AffinePolicyBytes(spec, weight, bias);
  if (!bytes.ok()) return bytes.status();
  return WriteFileAtomically(path, *bytes);
}

void SetTorchThreads(int threads) {
  at::set_num_threads(threads);
  // Debian's torch calls the system BLAS; when that is OpenBLAS its own thread pool fights
  // torch's OpenMP threads (measured: 2x slower PPO updates on 2 cores). Torch already
  // parallelizes around BLAS, so OpenBLAS gets one thread.
  using SetThreads = void (*)(int);
  if (auto set = reinterpret_cast<SetThreads>(dlsym(RTLD_DEFAULT, "openblas_set_num_threads"))) set(1);
}

PolicyCheckpoint::~PolicyCheckpoint() = default;

absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> PolicyCheckpoint::LoadFile(const std::string& path) {
  auto bytes = ReadFileToString(path, kMaxPolicyFileBytes);
  if (!bytes.ok()) {
    return absl::Status(bytes.status().code(), absl::StrCat("checkpoint_path: ", bytes.status().message()));
  }
  auto checkpoint = LoadBytes(*bytes);
  if (!checkpoint.ok()) {
    return absl::Status(checkpoint.status().code(), absl::StrCat(path, ": ", checkpoint.status().message()));
  }
  return checkpoint;
}

absl::StatusOr<std::unique_ptr<PolicyCheckpoint>> PolicyCheckpoint::LoadBytes(absl::string_view bytes) {
  std::unique_ptr<PolicyCheckpoint> checkpoint(new PolicyCheckpoint());
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}, {kCheckpointFamilyElitesFile, ""}};
  try {
    std::istringstream stream(std::string(bytes), std::ios::binary);
    checkpoint->module_ = std::make_unique<torch::jit::Module>(torch::jit::load(stream, torch::kCPU, extra));
    checkpoint->module_->eval();
  } catch (const std::exception& e) {
    // Torch's messages run to many lines; the first says what went wrong.
    std::string message = e.what();
    message = message.substr(0, message.find('\n'));
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: not a loadable TorchScript archive: ", message));
  }
  if (extra[kCheckpointSpecFile].empty()) {
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: no ", kCheckpointSpecFile, " inside the archive"));
  }
  auto spec = PolicySpec::FromJson(extra[kCheckpointSpecFile]);
  if (!spec.ok()) return absl::InvalidArgumentError(absl::StrCat("checkpoint: ", spec.status().message()));
  checkpoint->spec_ = *std::move(spec);
  if (checkpoint->spec_.is_family() && !extra[kCheckpointFamilyElitesFile].empty()) {
    auto elites = FamilyElitesFromJson(extra[kCheckpointFamilyElitesFile], static_cast<int>(checkpoint->spec_.family.size()));
    if (!elites.ok()) return absl::InvalidArgumentError(absl::StrCat("checkpoint: ", elites.status().message()));
    checkpoint->family_elites_ = *std::move(elites);
  }
  // A skills() that does not work costs composition only, not plain rollouts: kept as the reason.
  checkpoint->skills_error_ = checkpoint->ProbeSkills();
  if (!checkpoint->skills_error_.ok()) checkpoint->skill_parts_ = 0;
  return checkpoint;
}

absl::Status PolicyCheckpoint::NoSkills() const {
  if (!skills_error_.ok()) return absl::FailedPreconditionError(skills_error_.message());
  return absl::FailedPreconditionError("checkpoint: no skills() and act_with_z() methods");
}

absl::Status PolicyCheckpoint::ProbeSkills() {
  if (!module_->find_method("skills") || !module_->find_method("act_with_z")) return absl::OkStatus();
  // The exporter's name for the whole-body ablation's controller (learner/policy_export.h).
  part_controllers_ = !module_->hasattr("whole_body_controller_fc0_weight");
  try {
    torch::NoGradGuard no_grad;
    const torch::Tensor z = module_->get_method("skills")({torch::zeros({1, spec_.obs_size})}).toTensor();
    if (z.dim() != 3 || z.size(0) != 1 || z.size(1) < 1 || z.size(2) < 1 || z.size(1) > 1024 || z.size(2) > 4096) {
      return absl::InvalidArgumentError(absl::StrCat("checkpoint: skills() returned a ", z.dim(),
                                                     "-d tensor, expected [n, parts, embed_dim]"));
    }
    skill_parts_ = static_cast<int>(z.size(1));
    embed_dim_ = static_cast<int>(z.size(2));
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: skills() failed: ", message.substr(0, message.find('\n'))));
  }
  return absl::OkStatus();
}

absl::Status PolicyCheckpoint::CopyOut(const char* method, const at::Tensor& output, int n, int64_t row_size,
                                       float* out) {
  const torch::Tensor flat = output.to(torch::kFloat32).contiguous();
  if (flat.dim() < 2 || flat.size(0) != n || flat.numel() != n * row_size) {
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: ", method, " returned ", flat.numel(),
                                                   " values, expected ", n, " x ", row_size));
  }
  std::memcpy(out, flat.data_ptr<float>(), sizeof(float) * n * row_size);
  return absl::OkStatus();
}

absl::Status PolicyCheckpoint::Skills(const float* obs, int n, float* z) {
  if (!has_skills()) return NoSkills();
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    torch::NoGradGuard no_grad;
    torch::Tensor input = torch::from_blob(const_cast<float*>(obs), {n, spec_.obs_size}, torch::kFloat32);
    return CopyOut("skills()", module_->get_method("skills")({input}).toTensor(), n,
                   int64_t{skill_parts_} * embed_dim_, z);
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: skills() failed: ", message.substr(0, message.find('\n'))));
  }
}

absl::Status PolicyCheckpoint::ActWithZ(const float* obs, const float* z, int n, float* actions) {
  if (!has_skills()) return NoSkills();
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    torch::NoGradGuard no_grad;
    torch::Tensor input = torch::from_blob(const_cast<float*>(obs), {n, spec_.obs_size}, torch::kFloat32);
    torch::Tensor skills = torch::from_blob(const_cast<float*>(z), {n, skill_parts_, embed_dim_}, torch::kFloat32);
    return CopyOut("act_with_z()", module_->get_method("act_with_z")({input, skills}).toTensor(), n,
                   spec_.action_size, actions);
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(
        absl::StrCat("checkpoint: act_with_z() failed: ", message.substr(0, message.find('\n'))));
  }
}

bool PolicyCheckpoint::has_parameterization() const {
  return spec_.is_family() && module_->find_method("parameterization").has_value();
}

absl::StatusOr<std::vector<float>> PolicyCheckpoint::Parameterization(absl::Span<const double> u) {
  if (!has_parameterization()) {
    return absl::FailedPreconditionError("checkpoint: no parameterization network (a family run that has fitted none yet)");
  }
  const int64_t dims = static_cast<int64_t>(spec_.family.size()), frames = spec_.family_frames;
  if (static_cast<int64_t>(u.size()) != dims) {
    return absl::InvalidArgumentError(absl::StrCat("parameterization: ", u.size(), " parameters, expected ", dims));
  }
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    torch::NoGradGuard no_grad;
    const torch::Tensor a = torch::tensor(std::vector<double>(u.begin(), u.end()), torch::kFloat32);
    const torch::Tensor output = module_->get_method("parameterization")({a.unsqueeze(0).expand({frames, dims}).contiguous(),
                                                                         torch::linspace(0, 1, frames)})
                                     .toTensor();
    std::vector<float> out(static_cast<size_t>(frames) * spec_.action_size);
    if (absl::Status status = CopyOut("parameterization()", output, static_cast<int>(frames), spec_.action_size, out.data());
        !status.ok()) {
      return status;
    }
    return out;
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(
        absl::StrCat("checkpoint: parameterization() failed: ", message.substr(0, message.find('\n'))));
  }
}

absl::Status PolicyCheckpoint::Act(const float* obs, int n, float* actions) {
  std::lock_guard<std::mutex> lock(mutex_);
  try {
    torch::NoGradGuard no_grad;
    torch::Tensor input = torch::from_blob(const_cast<float*>(obs), {n, spec_.obs_size}, torch::kFloat32);
    torch::Tensor output = module_->forward({input}).toTensor().to(torch::kFloat32).contiguous();
    if (output.dim() != 2 || output.size(0) != n || output.size(1) != spec_.action_size) {
      return absl::InvalidArgumentError(absl::StrCat("checkpoint: forward returned shape ", output.sizes().vec().size(),
                                                     "-d, expected [", n, ", ", spec_.action_size, "]"));
    }
    std::memcpy(actions, output.data_ptr<float>(), sizeof(float) * n * spec_.action_size);
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat("checkpoint: forward failed: ", message.substr(0, message.find('\n'))));
  }
  return absl::OkStatus();
}

}  // namespace modskill
