#include "learner/tools/family_command.h"

#include <cstdio>

#include "absl/flags/declare.h"
#include "absl/flags/flag.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_format.h"
#include "common/atomic_file.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/log.h"
#include "learner/family/family_trainer.h"

ABSL_FLAG(std::string, family, "",
          "train a motor-skill family from this one clip (Lee et al. 2021) instead of a tracker; with --param");
ABSL_FLAG(std::vector<std::string>, param, {},
          "--family: a task parameter's range NAME=LO:HI or constraint NAME=VALUE; give --param once per "
          "parameter (the server's Describe lists them: gravity, body_mass_scale, jump_height, ...)");
ABSL_FLAG(int, family_net_every, 10, "--family: iterations between fits of the parameterization network P(a)");
// 0.1: the authors' public code admits no elite below F = 0.1.
ABSL_FLAG(double, family_acceptance, 0.1, "--family: fitness an elite needs to count as covering its parameters");
ABSL_FLAG(double, family_target_kl, 0.01,
          "--family: the KL per PPO minibatch step that steers the learning rate (divided or multiplied by 1.5 "
          "when the KL is above twice or below half of it); 0 keeps --learning_rate fixed");
ABSL_FLAG(double, family_termination_distance, 0,
          "--family: an episode fails when a body is farther from its reference (m); 0: the server's family "
          "default, 1 m");
ABSL_FLAG(std::vector<std::string>, family_eval, {},
          "--family: after training (--iterations 0: only), roll the policy out at these values of the first "
          "varied parameter (the others at mid-range) and write run_dir/family_eval.csv: apex, flight time, F");

ABSL_DECLARE_FLAG(std::vector<std::string>, servers);
ABSL_DECLARE_FLAG(std::string, run_dir);
ABSL_DECLARE_FLAG(bool, resume);
ABSL_DECLARE_FLAG(uint64_t, seed);
ABSL_DECLARE_FLAG(int, iterations);
ABSL_DECLARE_FLAG(double, time_budget_min);
ABSL_DECLARE_FLAG(int, envs_per_server);
ABSL_DECLARE_FLAG(int, horizon);
ABSL_DECLARE_FLAG(int, epochs);
ABSL_DECLARE_FLAG(double, learning_rate);
ABSL_DECLARE_FLAG(double, residual_scale);
ABSL_DECLARE_FLAG(std::string, tls_ca);

namespace modskill::learner {

std::vector<std::string> RepeatedFlagValues(int argc, char** argv, const std::string& name) {
  const std::string bare = "--" + name, with_value = bare + "=";
  std::vector<std::string> values;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    if (absl::StartsWith(arg, with_value)) {
      values.push_back(arg.substr(with_value.size()));
    } else if (arg == bare && i + 1 < argc) {
      values.push_back(argv[++i]);
    }
  }
  return values;
}

bool FamilyRequested() { return !absl::GetFlag(FLAGS_family).empty(); }

namespace {

int FamilyFail(const std::string& message, int code) {
  LogLine("modskill-learner: %s", message);
  return code;
}

absl::StatusOr<family::FamilyTrainerConfig> FamilyConfigFromFlags(const std::string& token,
                                                                 const std::vector<std::string>& params) {
  family::FamilyTrainerConfig config;
  const std::vector<std::string> servers = absl::GetFlag(FLAGS_servers);
  if (servers.size() != 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("--family: trains against one server; --servers names ", servers.size()));
  }
  auto ranges = ParseParamRanges(params);
  if (!ranges.ok()) return absl::InvalidArgumentError(absl::StrCat("--", ranges.status().message()));
  if (ranges->empty()) return absl::InvalidArgumentError("--family: needs at least one --param NAME=LO:HI");
  config.client.server = servers[0];
  config.client.token = token;
  config.client.tls_ca_file = absl::GetFlag(FLAGS_tls_ca);
  config.clip = absl::GetFlag(FLAGS_family);
  config.ranges = *std::move(ranges);
  config.run_dir = absl::GetFlag(FLAGS_run_dir);
  config.resume = absl::GetFlag(FLAGS_resume);
  config.seed = absl::GetFlag(FLAGS_seed);
  config.max_iterations = absl::GetFlag(FLAGS_iterations);
  config.max_minutes = absl::GetFlag(FLAGS_time_budget_min);
  if (absl::GetFlag(FLAGS_envs_per_server) > 0) config.num_envs = absl::GetFlag(FLAGS_envs_per_server);
  config.horizon = absl::GetFlag(FLAGS_horizon);
  if (absl::GetFlag(FLAGS_epochs) > 0) config.epochs = absl::GetFlag(FLAGS_epochs);
  if (absl::GetFlag(FLAGS_learning_rate) > 0) config.learning_rate = absl::GetFlag(FLAGS_learning_rate);
  config.residual_scale = absl::GetFlag(FLAGS_residual_scale);
  config.target_kl = absl::GetFlag(FLAGS_family_target_kl);
  config.termination_distance = absl::GetFlag(FLAGS_family_termination_distance);
  config.net_every = absl::GetFlag(FLAGS_family_net_every);
  config.coverage.acceptance = absl::GetFlag(FLAGS_family_acceptance);
  return config;
}

// --family_eval's values as parameter vectors: the first varied parameter takes each value, the
// others sit at the middle of their ranges.
absl::StatusOr<std::vector<std::vector<double>>> EvalPoints(const ParamSpace& space) {
  int varied = 0;
  while (varied < space.dims() && space.is_constraint(varied)) ++varied;
  if (varied == space.dims()) varied = 0;
  std::vector<std::vector<double>> points;
  for (const std::string& text : absl::GetFlag(FLAGS_family_eval)) {
    double value = 0;
    if (!absl::SimpleAtod(text, &value)) return absl::InvalidArgumentError(absl::StrCat("--family_eval: '", text, "' is not a number"));
    std::vector<double> a;
    for (const ParamRange& range : space.ranges()) a.push_back(0.5 * (range.lo + range.hi));
    a[varied] = value;
    points.push_back(a);
  }
  return points;
}

int EvaluateFamily(family::FamilyTrainer& trainer, const std::string& run_dir) {
  auto points = EvalPoints(trainer.space());
  if (!points.ok()) return FamilyFail(std::string(points.status().message()), 2);
  auto results = trainer.Evaluate(*points);
  if (!results.ok()) return FamilyFail(std::string(results.status().message()), 1);
  std::vector<std::string> names;
  for (const ParamRange& range : trainer.space().ranges()) names.push_back(range.name);
  std::string csv = absl::StrCat(absl::StrJoin(names, ","), ",apex_height_m,highest_effector_m,flight_s,fitness,steps,reached_end\n");
  for (const family::FamilyRolloutResult& r : *results) {
    absl::StrAppend(&csv, absl::StrJoin(r.params, ","), absl::StrFormat(",%.4f,%.4f,%.4f,%.4f,%d,%d\n", r.apex_height,
                                                                          r.highest_effector, r.flight_s, r.fitness, r.steps,
                                                                          r.reached_end));
  }
  std::fputs(csv.c_str(), stdout);
  if (absl::Status status = WriteFileAtomically(run_dir + "/family_eval.csv", csv); !status.ok()) {
    return FamilyFail(std::string(status.message()), 1);
  }
  return 0;
}

}  // namespace

int RunFamilyTraining(const std::string& token, const std::vector<std::string>& params, const std::atomic<bool>& stop) {
  auto config = FamilyConfigFromFlags(token, params);
  if (!config.ok()) return FamilyFail(std::string(config.status().message()), 2);
  auto trainer = family::FamilyTrainer::Create(*config);
  if (!trainer.ok()) {
    const bool bad_flag = trainer.status().code() == absl::StatusCode::kInvalidArgument;
    return FamilyFail(std::string(trainer.status().message()), bad_flag ? 2 : 1);
  }
  std::vector<std::string> shown;
  for (const ParamRange& range : config->ranges) shown.push_back(absl::StrCat(range.name, "=", range.lo, ":", range.hi));
  LogLine("training the family of %s over %s on %s, %d envs, run dir %s", config->clip, absl::StrJoin(shown, " "),
          config->client.server, config->num_envs, config->run_dir);
  absl::Status status = (*trainer)->Run([&stop] { return stop.load(); });
  if (!status.ok()) return FamilyFail(std::string(status.message()), 1);
  if (!absl::GetFlag(FLAGS_family_eval).empty()) {
    if (const int code = EvaluateFamily(**trainer, config->run_dir); code != 0) return code;
  }
  status = (*trainer)->Close();
  if (!status.ok()) return FamilyFail(std::string(status.message()), 1);
  return 0;
}

}  // namespace modskill::learner
