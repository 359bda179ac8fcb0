#include "learner/evaluation.h"

#include <algorithm>
#include <map>

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "common/policy/policy_checkpoint.h"
#include "common/wire/policy_spec_wire.h"

namespace modskill::learner {
namespace {

// The bodies the policy's task watches (Describe's TaskInfo.tracked_bodies) and their errors.
absl::Status AddTrackedBodies(const v1::EnvSpec& described, const std::string& checkpoint_bytes,
                              EvaluationReport* report) {
  auto checkpoint = PolicyCheckpoint::LoadBytes(checkpoint_bytes);
  if (!checkpoint.ok()) return checkpoint.status();
  for (const v1::TaskInfo& task : described.tasks()) {
    if (task.name() != (*checkpoint)->spec().task) continue;
    for (const std::string& body : task.tracked_bodies()) {
      const auto found = std::find(report->body_names.begin(), report->body_names.end(), body);
      if (found == report->body_names.end()) {
        return absl::InternalError(absl::StrCat("Describe: tracked body '", body, "' of task ", task.name(),
                                                " is not among body_names"));
      }
      const double error = report->body_error_mm[found - report->body_names.begin()];
      report->tracked_bodies.push_back(body);
      report->tracked_body_error_mm.push_back(error);
      report->tracked_g_mpjpe_mm += error / task.tracked_bodies_size();
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<EvaluationReport> Evaluate(SimulationClient& client, const std::string& checkpoint_name,
                                          const std::string& checkpoint_bytes, const std::vector<std::string>& clips,
                                          const std::function<void(const v1::RolloutFrame&)>& on_frame) {
  auto spec = client.Describe();
  if (!spec.ok()) return spec.status();
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(checkpoint_bytes);
  for (const std::string& clip : clips) request.add_clips(clip);
  request.set_termination(v1::EVALUATION);
  request.set_termination_distance(0.5f);
  request.set_stream_frames(on_frame != nullptr);
  auto metrics = client.Rollout(request, on_frame);
  if (!metrics.ok()) return metrics.status();
  if (metrics->empty()) return absl::InternalError("rollout: no clip metrics returned");
  EvaluationReport report;
  report.checkpoint = checkpoint_name;
  report.clips = *metrics;
  report.body_names.assign(spec->body_names().begin(), spec->body_names().end());
  const int bodies = report.body_names.size();
  const int parts = (*metrics)[0].part_error_mm_size();
  report.body_error_mm.assign(bodies, 0.0);
  report.part_error_mm.assign(parts, 0.0);
  double frames = 0;
  int successes = 0;
  for (const v1::ClipMetrics& clip : *metrics) {
    const double n = clip.steps() + 1;
    frames += n;
    successes += clip.success();
    report.g_mpjpe_mm += n * clip.g_mpjpe_mm();
    report.mpjpe_mm += n * clip.mpjpe_mm();
    report.acc_error_mm += n * clip.acc_error_mm();
    report.vel_error_mm += n * clip.vel_error_mm();
    for (int b = 0; b < std::min(bodies, clip.body_error_mm_size()); ++b) report.body_error_mm[b] += n * clip.body_error_mm(b);
    for (int p = 0; p < std::min(parts, clip.part_error_mm_size()); ++p) report.part_error_mm[p] += n * clip.part_error_mm(p);
  }
  report.success_rate = static_cast<double>(successes) / metrics->size();
  report.g_mpjpe_mm /= frames;
  report.mpjpe_mm /= frames;
  report.acc_error_mm /= frames;
  report.vel_error_mm /= frames;
  for (double& e : report.body_error_mm) e /= frames;
  for (double& e : report.part_error_mm) e /= frames;
  // The part names of the checkpoint's layout: the one the server offers with this many parts.
  for (const std::string& layout : spec->part_layouts()) {
    auto described = client.Describe(layout);
    if (described.ok() && described->parts_size() == parts) {
      for (const v1::BodyPart& part : described->parts()) report.part_names.push_back(part.name());
      break;
    }
  }
  if (absl::Status status = AddTrackedBodies(*spec, checkpoint_bytes, &report); !status.ok()) return status;
  // One rollout at 0.5 m also answers stricter distances: a clip succeeds at d when its mean
  // body error never exceeded d (the trajectory up to that point is the same).
  for (int k = 0; k <= 6; ++k) {
    const double distance = 0.5 - 0.05 * k;
    int ok = 0;
    for (const v1::ClipMetrics& clip : *metrics) ok += clip.max_mean_body_error_m() <= distance;
    report.success_at_distance.emplace_back(distance, static_cast<double>(ok) / metrics->size());
  }
  return report;
}

std::string EvaluationReport::ToJson() const {
  nlohmann::json json;
  json["checkpoint"] = checkpoint;
  json["clips_evaluated"] = clips.size();
  json["success_rate"] = success_rate;
  json["g_mpjpe_mm"] = g_mpjpe_mm;
  json["mpjpe_mm"] = mpjpe_mm;
  json["acc_error_mm_per_frame2"] = acc_error_mm;
  json["vel_error_mm_per_frame"] = vel_error_mm;
  for (size_t b = 0; b < body_error_mm.size(); ++b) json["body_error_mm"][body_names[b]] = body_error_mm[b];
  for (size_t p = 0; p < part_error_mm.size(); ++p) {
    json["part_error_mm"][p < part_names.size() ? part_names[p] : absl::StrCat("part", p)] = part_error_mm[p];
  }
  for (const auto& [distance, rate] : success_at_distance) json["success_at_distance"][absl::StrFormat("%.2f", distance)] = rate;
  if (!tracked_bodies.empty()) {
    json["tracked_g_mpjpe_mm"] = tracked_g_mpjpe_mm;
    for (size_t b = 0; b < tracked_bodies.size(); ++b) json["tracked_body_error_mm"][tracked_bodies[b]] = tracked_body_error_mm[b];
  }
  for (const v1::ClipMetrics& clip : clips) {
    nlohmann::json c;
    c["clip"] = clip.clip();
    c["success"] = clip.success();
    c["steps"] = clip.steps();
    c["g_mpjpe_mm"] = clip.g_mpjpe_mm();
    c["mpjpe_mm"] = clip.mpjpe_mm();
    c["acc_error_mm"] = clip.acc_error_mm();
    c["vel_error_mm"] = clip.vel_error_mm();
    c["max_mean_body_error_m"] = clip.max_mean_body_error_m();
    json["clips"].push_back(c);
  }
  return json.dump(1);
}

std::string EvaluationReport::ToMarkdown(const std::string& method) const {
  std::string md = "| Method | Succ ↑ | E_g-mpjpe ↓ | E_mpjpe ↓ | E_acc ↓ | E_vel ↓ |\n|---|---|---|---|---|---|\n";
  absl::StrAppendFormat(&md, "| %s | %.1f %% | %.1f | %.1f | %.1f | %.1f |\n", method, 100 * success_rate, g_mpjpe_mm,
                        mpjpe_mm, acc_error_mm, vel_error_mm);
  absl::StrAppend(&md, "\nErrors in mm (E_acc in mm/frame², E_vel in mm/frame), ", clips.size(),
                  " clips, evaluation termination at 0.5 m mean body error");
  if (!tracked_bodies.empty()) {
    absl::StrAppend(&md, " over the tracked bodies (", absl::StrJoin(tracked_bodies, ", "),
                    "); the errors above are every body's.\n\n| Tracked body | E_g-mpjpe (mm) |\n|---|---|\n");
    for (size_t b = 0; b < tracked_bodies.size(); ++b) {
      absl::StrAppendFormat(&md, "| %s | %.1f |\n", tracked_bodies[b], tracked_body_error_mm[b]);
    }
    absl::StrAppendFormat(&md, "| **mean** | %.1f |\n", tracked_g_mpjpe_mm);
  } else {
    absl::StrAppend(&md, ".\n");
  }
  absl::StrAppend(&md, "\n| Termination distance (m) |");
  for (const auto& [distance, rate] : success_at_distance) absl::StrAppendFormat(&md, " %.2f |", distance);
  absl::StrAppend(&md, "\n|---|");
  for (size_t k = 0; k < success_at_distance.size(); ++k) absl::StrAppend(&md, "---|");
  absl::StrAppend(&md, "\n| Success |");
  for (const auto& [distance, rate] : success_at_distance) absl::StrAppendFormat(&md, " %.1f %% |", 100 * rate);
  absl::StrAppend(&md, "\n\n| Part | Mean body error (mm) |\n|---|---|\n");
  for (size_t p = 0; p < part_error_mm.size(); ++p) {
    absl::StrAppendFormat(&md, "| %s | %.1f |\n", p < part_names.size() ? part_names[p] : absl::StrCat("part", p),
                          part_error_mm[p]);
  }
  absl::StrAppend(&md, "\n| Clip | Succ | Steps | E_g-mpjpe | E_mpjpe | E_acc | E_vel |\n|---|---|---|---|---|---|---|\n");
  for (const v1::ClipMetrics& clip : clips) {
    absl::StrAppendFormat(&md, "| %s | %s | %d | %.1f | %.1f | %.1f | %.1f |\n", clip.clip(), clip.success() ? "yes" : "no",
                          clip.steps(), clip.g_mpjpe_mm(), clip.mpjpe_mm(), clip.acc_error_mm(), clip.vel_error_mm());
  }
  return md;
}

absl::StatusOr<std::string> OpenLoopReferencePolicy(const v1::EnvSpec& spec) {
  ActionMapping residual;
  residual.mode = ActionMode::kResidual;
  return AffinePolicyBytes(PolicySpecOf(spec, residual), {}, {});
}

std::string CompareWithBaseline(const EvaluationReport& policy, const EvaluationReport& baseline) {
  std::map<std::string, const v1::ClipMetrics*> reference;
  for (const v1::ClipMetrics& clip : baseline.clips) reference[clip.clip()] = &clip;
  std::string out = absl::StrFormat(
      "\nAgainst the open-loop reference (PD targets = the reference pose, no learning), same clips and protocol:\n\n"
      "| clip | policy: steps tracked | policy: E_mpjpe (mm) | reference: steps tracked | reference: E_mpjpe (mm) |\n"
      "|---|---|---|---|---|\n");
  double policy_steps = 0, reference_steps = 0;
  for (const v1::ClipMetrics& clip : policy.clips) {
    auto it = reference.find(clip.clip());
    if (it == reference.end()) continue;
    policy_steps += clip.steps();
    reference_steps += it->second->steps();
    absl::StrAppendFormat(&out, "| %s | %d%s | %.1f | %d%s | %.1f |\n", clip.clip(), clip.steps(),
                          clip.success() ? " (all)" : "", clip.mpjpe_mm(), it->second->steps(),
                          it->second->success() ? " (all)" : "", it->second->mpjpe_mm());
  }
  absl::StrAppendFormat(&out, "| **all** (Succ, E_mpjpe) | %.0f steps, %.1f %% | %.1f | %.0f steps, %.1f %% | %.1f |\n",
                        policy_steps, 100 * policy.success_rate, policy.mpjpe_mm, reference_steps,
                        100 * baseline.success_rate, baseline.mpjpe_mm);
  return out;
}

}  // namespace modskill::learner
