#include "learner/policy_upgrade.h"

#include <cstdio>
#include <exception>
#include <sstream>
#include <utility>

#include <torch/script.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/policy/family_elites.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/physics_wire.h"
#include "learner/model_config.h"
#include "learner/policy_export.h"

namespace modskill::learner {
namespace {

// The largest |old forward - new forward| (and |old forward - act_with_z(skills)| where the new
// file defines them) over random raw observations, scaled like real ones.
absl::StatusOr<double> ForwardDifference(const std::string& old_path, const std::string& new_path, int64_t obs_size) {
  try {
    torch::NoGradGuard no_grad;
    torch::manual_seed(1);
    const torch::Tensor obs = torch::randn({64, obs_size}) * 2.0;
    torch::jit::Module before = torch::jit::load(old_path), after = torch::jit::load(new_path);
    const torch::Tensor a = before.forward({obs}).toTensor(), b = after.forward({obs}).toTensor();
    double difference = (a - b).abs().max().item<double>();
    if (after.find_method("skills") && after.find_method("act_with_z")) {
      const torch::Tensor composed =
          after.get_method("act_with_z")({obs, after.get_method("skills")({obs}).toTensor()}).toTensor();
      difference = std::max(difference, (a - composed).abs().max().item<double>());
    }
    return difference;
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("checking the export: ", message.substr(0, message.find('\n'))));
  }
}

// The physics the upgraded file records: its own, which must be the server's, or the server's.
absl::Status TakePhysics(const v1::EnvSpec& server_spec, const std::string& path, PolicySpec& spec,
                         PolicyUpgrade& upgrade) {
  const PhysicsSettings server = PhysicsOf(server_spec);
  if (spec.physics.recorded()) {
    if (std::string difference = PhysicsDifference(spec.physics, server, "this server's"); !difference.empty()) {
      return absl::FailedPreconditionError(absl::StrCat(path, ": trained with ", difference,
                                                        "; upgrade it against a server with the physics it was trained in"));
    }
  } else if (server.recorded()) {
    spec.physics = server;
    upgrade.physics_added = true;
  }
  upgrade.physics = spec.physics;
  return absl::OkStatus();
}

// Moves the staged file onto `out` when the check passed; removes it otherwise.
absl::Status Commit(const std::string& staged, const std::string& out, const std::string& in,
                    const absl::StatusOr<double>& difference) {
  if (!difference.ok() || *difference > 1e-5) {
    std::remove(staged.c_str());
    if (!difference.ok()) return difference.status();
    return absl::InternalError(absl::StrCat("the re-exported forward differs from ", in, " by ", *difference));
  }
  if (std::rename(staged.c_str(), out.c_str()) != 0) {
    std::remove(staged.c_str());
    return absl::InternalError(absl::StrCat(out, ": cannot move ", staged, " there"));
  }
  return absl::OkStatus();
}

// A task policy (a head over frozen skills) or a family is exported by today's script already: its
// archive is saved again as it is, with the spec that records the physics (and a family's elites).
absl::Status ResaveWithSpec(const std::string& in, const PolicySpec& spec, const std::string& staged) {
  try {
    torch::jit::ExtraFilesMap extra{{kCheckpointFamilyElitesFile, ""}};
    torch::jit::Module module = torch::jit::load(in, torch::kCPU, extra);
    if (extra[kCheckpointFamilyElitesFile].empty()) extra.erase(kCheckpointFamilyElitesFile);
    extra[kCheckpointSpecFile] = spec.ToJson();
    std::ostringstream bytes(std::ios::binary);
    module.save(bytes, extra);
    return WriteFileAtomically(staged, bytes.str());
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InternalError(absl::StrCat("re-saving ", in, ": ", message.substr(0, message.find('\n'))));
  }
}

// Saves `in` again as it is but for `spec`, checks its forward, and moves it onto `out`.
absl::StatusOr<PolicyUpgrade> Resave(const std::string& in, const PolicySpec& spec, const std::string& out,
                                     PolicyUpgrade upgrade) {
  const std::string staged = out + ".upgrade";
  if (absl::Status status = ResaveWithSpec(in, spec, staged); !status.ok()) return status;
  const absl::StatusOr<double> difference = ForwardDifference(in, staged, spec.obs_size);
  if (absl::Status status = Commit(staged, out, in, difference); !status.ok()) return status;
  upgrade.forward_difference = *difference;
  return upgrade;
}

}  // namespace

absl::StatusOr<PolicyUpgrade> UpgradePolicy(ExportedPolicy exported, const v1::EnvSpec& server_spec,
                                            const std::string& out) {
  PolicyUpgrade upgrade;
  if (absl::Status status = TakePhysics(server_spec, exported.path, exported.spec, upgrade); !status.ok()) {
    return status;
  }
  if (exported.spec.task != kTrackingTask) return Resave(exported.path, exported.spec, out, upgrade);
  // Written beside OUT first, so that a failed check leaves OUT alone.
  const std::string staged = out + ".upgrade";
  const NetworkLayout layout = LayoutFromWireSpec(server_spec);
  if (absl::Status valid = layout.Validate(); !valid.ok()) return valid;
  auto rebuilt = RebuildTracker(exported, layout);
  if (!rebuilt.ok()) return rebuilt.status();
  // What the rebuilt controllers read, also for files from before the spec recorded it.
  exported.spec.controller_input = ControllerInputName(rebuilt->policy->config().controller_input);
  if (absl::Status status = ExportPolicy(rebuilt->policy, rebuilt->obs_norm, exported.spec, staged); !status.ok()) {
    return status;
  }
  const absl::StatusOr<double> difference = ForwardDifference(exported.path, staged, layout.obs_size);
  if (absl::Status status = Commit(staged, out, exported.path, difference); !status.ok()) return status;
  upgrade.rebuilt = true;
  upgrade.parts = static_cast<int>(layout.parts.size());
  upgrade.embed_dim = rebuilt->policy->config().embed_dim;
  upgrade.forward_difference = *difference;
  return upgrade;
}

absl::StatusOr<PolicyUpgrade> UpgradeFamilyPolicy(const std::string& in, const v1::EnvSpec& family_session_spec,
                                                  const std::string& out) {
  torch::jit::ExtraFilesMap extra{{kCheckpointSpecFile, ""}};
  try {
    torch::jit::load(in, torch::kCPU, extra);
  } catch (const std::exception& e) {
    std::string message = e.what();
    return absl::InvalidArgumentError(absl::StrCat(in, ": not a policy file (", message.substr(0, message.find('\n')), ")"));
  }
  auto spec = PolicySpec::FromJson(extra[kCheckpointSpecFile]);
  if (!spec.ok()) return absl::InvalidArgumentError(absl::StrCat(in, ": ", spec.status().message()));
  if (!spec->is_family()) return absl::InvalidArgumentError(absl::StrCat(in, ": not a motor-skill family's policy"));
  // A server's Describe reports its own servos, not the stable PD every family session runs.
  if (family_session_spec.family_size() == 0) {
    return absl::InvalidArgumentError("the spec to take physics from is not a family session's");
  }
  PolicyUpgrade upgrade;
  if (absl::Status status = TakePhysics(family_session_spec, in, *spec, upgrade); !status.ok()) return status;
  return Resave(in, *spec, out, upgrade);
}

}  // namespace modskill::learner
