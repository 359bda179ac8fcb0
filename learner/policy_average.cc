#include "learner/policy_average.h"

#include <sstream>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "learner/policy_import.h"

namespace modskill::learner {
namespace {

// OK when `other` holds the same spec and tensors (names, shapes, dtypes) as `first`.
absl::Status SameShape(const ExportedPolicy& first, const ExportedPolicy& other) {
  if (other.spec.ToJson() != first.spec.ToJson()) {
    return absl::InvalidArgumentError(
        absl::StrCat(other.path, ": its spec differs from ", first.path, "'s (another run, task or layout?)"));
  }
  if (other.tensors.size() != first.tensors.size()) {
    return absl::InvalidArgumentError(absl::StrCat(other.path, ": ", other.tensors.size(), " tensors, ", first.path,
                                                   " has ", first.tensors.size()));
  }
  for (const auto& [name, tensor] : first.tensors) {
    auto found = other.tensors.find(name);
    if (found == other.tensors.end()) {
      return absl::InvalidArgumentError(absl::StrCat(other.path, ": no tensor ", name, " (", first.path, " has one)"));
    }
    if (!found->second.sizes().equals(tensor.sizes()) || found->second.scalar_type() != tensor.scalar_type()) {
      return absl::InvalidArgumentError(absl::StrCat(other.path, ": ", name, " is ", c10::str(found->second.sizes()),
                                                     ", in ", first.path, " ", c10::str(tensor.sizes())));
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::Status AveragePolicies(const std::vector<std::string>& inputs, const std::string& out) {
  if (inputs.size() < 2) return absl::InvalidArgumentError("averaging needs at least two policy files");
  std::vector<ExportedPolicy> policies;
  for (const std::string& path : inputs) {
    auto policy = ReadExportedPolicy(path);
    if (!policy.ok()) return policy.status();
    if (!policies.empty()) {
      if (absl::Status same = SameShape(policies.front(), *policy); !same.ok()) return same;
    }
    policies.push_back(*std::move(policy));
  }
  auto bytes = ReadFileToString(inputs.front(), kMaxPolicyFileBytes);
  if (!bytes.ok()) return bytes.status();
  try {
    torch::NoGradGuard no_grad;
    std::istringstream stream(*bytes, std::ios::binary);
    torch::jit::Module module = torch::jit::load(stream, torch::kCPU);
    for (const auto& [name, tensor] : policies.front().tensors) {
      if (!tensor.is_floating_point()) continue;  // counts and the like stay the first file's
      torch::Tensor sum = torch::zeros_like(tensor, torch::kFloat64);
      for (const ExportedPolicy& policy : policies) sum += policy.tensors.at(name).to(torch::kFloat64);
      module.setattr(name, (sum / static_cast<double>(policies.size())).to(tensor.scalar_type()));
    }
    std::ostringstream written(std::ios::binary);
    module.save(written, {{kCheckpointSpecFile, policies.front().spec.ToJson()}});
    return WriteFileAtomically(out, written.str());
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("averaging into ", out, ": ", message.substr(0, message.find('\n'))));
  }
}

}  // namespace modskill::learner
