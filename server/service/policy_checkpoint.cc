#include "server/service/policy_checkpoint.h"

#include <dlfcn.h>

#include <cmath>
#include <cstring>
#include <sstream>

#include <nlohmann/json.hpp>
#include <ATen/Parallel.h>
#include <torch/script.h>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "server/core/atomic_file.h"
#include "server/core/shown_value.h"

namespace modskill {
namespace {

// Largest observation or action vector a policy file may declare (the humanoid's are ~1000).
constexpr int64_t kMaxPolicyVectorSize = 1 << 20;

}  // namespace

PolicySpec PolicySpec::FromEnvSpec(const EnvSpec& spec) {
  PolicySpec policy;
  policy.part_layout = spec.layout.name;
  policy.obs_size = spec.obs_size;
  policy.action_size = spec.action_size;
  policy.joint_names = spec.joint_names;
  policy.control_dt = spec.control_dt;
  return policy;
}

std::string PolicySpec::ToJson() const {
  nlohmann::json json;
  json["part_layout"] = part_layout;
  json["obs_size"] = obs_size;
  json["action_size"] = action_size;
  json["joint_names"] = joint_names;
  json["control_dt"] = control_dt;
  json["action_mode"] = ActionModeName(action.mode);
  json["residual_scale"] = action.residual_scale;
  return json.dump(1);
}

absl::StatusOr<PolicySpec> PolicySpec::FromJson(absl::string_view text) {
  nlohmann::json json = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded() || !json.is_object()) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": not a JSON object"));
  }
  PolicySpec spec;
  // Sizes are read as they are written, not cast: 2^40 must not become 0.
  auto size = [&](const char* key) -> absl::StatusOr<int> {
    const nlohmann::json& value = json.at(key);
    if (!value.is_number_integer() || value.get<int64_t>() < 1 || value.get<int64_t>() > kMaxPolicyVectorSize) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", key, ": ", value.dump().substr(0, 32),
                                                     " is not an integer in [1, ", kMaxPolicyVectorSize, "]"));
    }
    return static_cast<int>(value.get<int64_t>());
  };
  try {
    spec.part_layout = json.at("part_layout").get<std::string>();
    if (spec.part_layout.size() > kMaxShownValueBytes) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": part_layout: ", spec.part_layout.size(),
                                                     " characters, longer than any layout name"));
    }
    auto obs_size = size("obs_size");
    if (!obs_size.ok()) return obs_size.status();
    spec.obs_size = *obs_size;
    auto action_size = size("action_size");
    if (!action_size.ok()) return action_size.status();
    spec.action_size = *action_size;
    spec.joint_names = json.at("joint_names").get<std::vector<std::string>>();
    if (static_cast<int64_t>(spec.joint_names.size()) > kMaxPolicyVectorSize) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": joint_names: too many"));
    }
    spec.control_dt = json.at("control_dt").get<double>();
    if (!(spec.control_dt > 0 && spec.control_dt < 10)) {
      return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": control_dt: ", spec.control_dt,
                                                     " is not in (0, 10) s"));
    }
    if (json.contains("action_mode")) {
      auto mode = ParseActionMode(json.at("action_mode").get<std::string>());
      if (!mode.ok()) return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": action_mode: ", mode.status().message()));
      spec.action.mode = *mode;
    }
    if (json.contains("residual_scale")) spec.action.residual_scale = json.at("residual_scale").get<double>();
  } catch (const nlohmann::json::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", ShownValue(e.what())));
  }
  if (absl::Status status = spec.action.Validate(); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointSpecFile, ": ", status.message()));
  }
  return spec;
}

absl::Status PolicySpec::CheckCompatible(const EnvSpec& server) const {
  auto mismatch = [](absl::string_view field, const auto& mine, const auto& theirs) {
    return absl::FailedPreconditionError(absl::StrCat("checkpoint: trained with ", field, " = ", mine,
                                                      ", this server has ", theirs));
  };
  if (part_layout != server.layout.name) return mismatch("part_layout", part_layout, server.layout.name);
  if (obs_size != server.obs_size) return mismatch("obs_size", obs_size, server.obs_size);
  if (action_size != server.action_size) return mismatch("action_size", action_size, server.action_size);
  if (std::abs(control_dt - server.control_dt) > 1e-9) return mismatch("control_dt", control_dt, server.control_dt);
  if (joint_names != server.joint_names) {
    return absl::FailedPreconditionError("checkpoint: trained with another joint order (joint_names differ)");
  }
  return absl::OkStatus();
}

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
  auto bytes = ReadFileToString(path, size_t{2} << 30);
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
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}};
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
  return checkpoint;
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
