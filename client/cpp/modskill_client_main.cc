// modskill-client: the command line of a modskill simulation server (see
// proto/modskill/v1/modskill.proto): the env spec, the motion library, server stats, uploads,
// checkpoint evaluation (rollout) and a stepping throughput check (simulate).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <memory>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/reflection.h"
#include "absl/flags/usage.h"
#include "absl/flags/usage_config.h"
#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/time/time.h"
#include "client/cpp/add_motions_command.h"
#include "client/cpp/cli_output.h"
#include "client/cpp/describe_command.h"
#include "client/cpp/family_command.h"
#include "client/cpp/motions_command.h"
#include "client/cpp/rollout_command.h"
#include "client/cpp/simulate_command.h"
#include "client/cpp/simulation_client.h"
#include "client/cpp/skill_commands.h"
#include "client/cpp/stats_command.h"

ABSL_FLAG(std::string, server, "127.0.0.1:50051", "server address, host:port");
ABSL_FLAG(std::string, auth_token_file, "", "file holding the server's token (sent as 'authorization: Bearer <token>')");
ABSL_FLAG(std::string, tls_ca, "", "PEM root certificates: connect with TLS, trusting these roots");
ABSL_FLAG(std::string, tls_server_name, "", "name to check in the server certificate (default: the host of --server)");
ABSL_FLAG(double, timeout_s, 10, "seconds to wait for the server to answer when connecting");
ABSL_FLAG(std::string, part_layout, "", "describe, simulate: part layout (empty: the server's default)");
ABSL_FLAG(std::string, checkpoint, "",
          "rollout: TorchScript checkpoint; a path the server reads (relative paths are made absolute here), "
          "or with --upload a local file whose bytes are sent");
ABSL_FLAG(std::vector<std::string>, clip, {},
          "rollout, simulate: clip names, repeated or comma-separated (empty: every clip)");
ABSL_FLAG(std::string, out, "",
          "rollout: write metrics, per-body errors (and frames) as JSON to this file; skills, compose: the "
          "directory to write skills.json, or compose.json and compose.html, into");
ABSL_FLAG(bool, upload, true,
          "rollout: send the checkpoint file's bytes; false: send its path, which the server reads only from its "
          "--checkpoint_dir directories");
ABSL_FLAG(std::string, html, "",
          "rollout: write a self-contained viewer page (the policy's character beside its reference, every clip) "
          "to this file");
ABSL_FLAG(std::string, base, "", "compose: the clip the character tracks");
ABSL_FLAG(std::string, source, "", "compose: the clip whose z the --parts take");
ABSL_FLAG(std::vector<std::string>, parts, {}, "compose: part names of the checkpoint's layout, comma-separated");
ABSL_FLAG(bool, interpolate, false,
          "compose: interpolate the parts' z from the base clip's own (start) to the source's (end) instead of swapping");
ABSL_FLAG(int, max_steps, 0, "skills, compose: steps per clip at most (0: the clip's length)");
ABSL_FLAG(bool, frames, false, "rollout: stream per-frame simulated and reference body positions into --out");
ABSL_FLAG(int, envs, 16, "simulate: envs in the session");
ABSL_FLAG(int, steps, 100, "simulate: steps to take");
ABSL_FLAG(std::string, actions, "zero", "simulate: zero or random (uniform in [-1, 1])");
ABSL_FLAG(uint64_t, seed, 1, "simulate: seed of the session and of the random actions");
ABSL_FLAG(std::vector<std::string>, param, {},
          "rollout, family: a motor-skill family's task parameter NAME=VALUE (e.g. gravity=6), repeated or "
          "comma-separated; the ones left out run at the middle of their trained range");
ABSL_FLAG(int, nearest_elites, 0, "family: elites to list, nearest first (0: 5)");

namespace modskill {
namespace {

constexpr char kUsage[] = R"(usage: modskill-client <command> [flags] [args]

commands:
  describe [--part_layout 5part]   the env spec: sizes, control dt, layouts, one line per body part
  motions                          the server's motion library, one line per clip
  stats                            server totals, live sessions and their 5 most sampled clips
  add-motions FILE...              upload clips (.npz .bvh .txt .msclip) to the server's library
  rollout --checkpoint F [--clip NAME...] [--out F.json] [--upload] [--frames] [--html F.html]
          [--param NAME=VALUE...]  evaluate a TorchScript policy on clips (default: every clip); a
                                   motor-skill family's at task parameters (--param gravity=6)
  family --checkpoint F [--param NAME=VALUE...] [--nearest_elites K] [--out F.json]
                                   a family's ranges, its elites nearest a and P(a), the edited motion
  skills --checkpoint F --clip NAME... --out DIR [--max_steps N]
                                   record a tracker's per-part z on clips: DIR/skills.json with a 2-D PCA
  compose --checkpoint F --base CLIP --source CLIP --parts NAME[,NAME] [--interpolate] --out DIR
                                   the base clip with the parts' z from the source clip (swapped or
                                   interpolated): DIR/compose.json and the viewer page DIR/compose.html
  simulate [--envs N] [--steps K] [--actions zero|random] [--seed S] [--part_layout L] [--clip NAME...]
                                   step a session and report env steps/s, reward, message sizes

common flags:
  --server host:port (127.0.0.1:50051)  --auth_token_file F  --tls_ca F  --tls_server_name NAME
  --timeout_s S (10)
'modskill-client --help' lists every flag.)";

constexpr int kUsageError = 2;

int Usage(const std::string& message) {
  std::fprintf(stderr, "error: %s\n\n%s\n", message.c_str(), kUsage);
  return kUsageError;
}

// The flags that may be repeated, every value collected.
struct RepeatedFlags {
  std::vector<std::string> clips;
  std::vector<std::pair<std::string, double>> params;  // --param NAME=VALUE
};

// "NAME=VALUE[,NAME=VALUE...]" -> params; false with `error` for a malformed entry.
bool ParseParams(absl::string_view value, std::vector<std::pair<std::string, double>>* params, std::string* error) {
  for (absl::string_view entry : absl::StrSplit(value, ',', absl::SkipWhitespace())) {
    const size_t eq = entry.find('=');
    double number = 0;
    if (eq == absl::string_view::npos || eq == 0 || !absl::SimpleAtod(entry.substr(eq + 1), &number) ||
        !std::isfinite(number)) {
      *error = absl::StrCat("--param: '", entry, "' is not NAME=VALUE with a finite number (e.g. gravity=6)");
      return false;
    }
    params->emplace_back(std::string(entry.substr(0, eq)), number);
  }
  return true;
}

// absl keeps only the last of repeated flags and exits with 1 on a bad one. This pass runs first:
// it collects every --clip and --param value (repeated and comma-separated) and reports an
// unknown flag or a malformed value as a usage error.
bool PrescanFlags(int argc, char** argv, RepeatedFlags* repeated, std::string* error) {
  for (int i = 1; i < argc; ++i) {
    absl::string_view arg = argv[i];
    if (arg == "--") break;
    if (arg.size() < 2 || arg[0] != '-') continue;
    arg.remove_prefix(arg[1] == '-' ? 2 : 1);
    absl::string_view name = arg;
    absl::string_view value;
    bool has_value = false;
    if (const size_t eq = arg.find('='); eq != absl::string_view::npos) {
      name = arg.substr(0, eq);
      value = arg.substr(eq + 1);
      has_value = true;
    }
    // absl's usage pseudo-flags (--help, --helpfull, ...) are left to absl.
    static const char* const kUsageFlags[] = {"help",    "helpfull", "helpshort",      "helppackage",
                                              "helpon",  "helpmatch", "only_check_args", "version"};
    if (std::find(std::begin(kUsageFlags), std::end(kUsageFlags), name) != std::end(kUsageFlags)) continue;
    absl::CommandLineFlag* flag = absl::FindCommandLineFlag(name);
    if (flag == nullptr && !has_value && absl::StartsWith(name, "no")) {
      absl::CommandLineFlag* negated = absl::FindCommandLineFlag(name.substr(2));
      if (negated != nullptr && negated->IsOfType<bool>()) continue;  // --noupload
    }
    if (flag == nullptr) {
      *error = absl::StrCat("unknown flag --", name);
      return false;
    }
    if (!has_value) {
      if (flag->IsOfType<bool>()) continue;
      if (i + 1 >= argc) {
        *error = absl::StrCat("--", name, " needs a value");
        return false;
      }
      value = argv[++i];
    }
    // absl's own flags (flagfile, fromenv, ...) are left to absl.
    if (name == "flagfile" || name == "fromenv" || name == "tryfromenv" || name == "undefok") continue;
    std::string parse_error;
    if (!flag->ParseFrom(value, &parse_error)) {
      *error = absl::StrCat("--", name, ": ", parse_error);
      return false;
    }
    if (name == "clip") {
      for (absl::string_view clip : absl::StrSplit(value, ',', absl::SkipWhitespace())) repeated->clips.emplace_back(clip);
    }
    if (name == "param" && !ParseParams(value, &repeated->params, error)) return false;
  }
  return true;
}

absl::StatusOr<std::unique_ptr<SimulationClient>> Connect() {
  ClientOptions options;
  options.server = absl::GetFlag(FLAGS_server);
  options.tls_ca_file = absl::GetFlag(FLAGS_tls_ca);
  options.tls_server_name = absl::GetFlag(FLAGS_tls_server_name);
  options.connect_timeout = absl::Seconds(absl::GetFlag(FLAGS_timeout_s));
  if (!absl::GetFlag(FLAGS_auth_token_file).empty()) {
    auto token = ReadTokenFile(absl::GetFlag(FLAGS_auth_token_file));
    if (!token.ok()) return absl::Status(token.status().code(), absl::StrCat("--auth_token_file: ", token.status().message()));
    options.token = *std::move(token);
  }
  auto client = SimulationClient::Connect(options);
  if (!client.ok() && absl::StartsWith(client.status().message(), "tls_ca:")) {
    return absl::Status(client.status().code(), absl::StrCat("--", client.status().message()));
  }
  return client;
}

// Runs the checked command with its options from the flags; returns the exit code.
int RunCommand(SimulationClient& client, const std::string& command, const std::vector<std::string>& operands,
               const RepeatedFlags& repeated) {
  const std::vector<std::string>& clips = repeated.clips;
  if (command == "describe") return cli::Describe(client, absl::GetFlag(FLAGS_part_layout));
  if (command == "motions") return cli::Motions(client);
  if (command == "stats") return cli::Stats(client);
  if (command == "add-motions") return cli::AddMotions(client, operands);
  if (command == "skills" || command == "compose") {
    cli::SkillOptions options;
    options.checkpoint = absl::GetFlag(FLAGS_checkpoint);
    options.clips = clips;
    options.out_dir = absl::GetFlag(FLAGS_out);
    options.base = absl::GetFlag(FLAGS_base);
    options.source = absl::GetFlag(FLAGS_source);
    options.parts = absl::GetFlag(FLAGS_parts);
    options.interpolate = absl::GetFlag(FLAGS_interpolate);
    options.max_steps = absl::GetFlag(FLAGS_max_steps);
    return command == "skills" ? cli::RecordSkills(client, options) : cli::Compose(client, options);
  }
  if (command == "rollout") {
    cli::RolloutOptions options;
    options.checkpoint = absl::GetFlag(FLAGS_checkpoint);
    options.upload = absl::GetFlag(FLAGS_upload);
    options.clips = clips;
    options.out = absl::GetFlag(FLAGS_out);
    options.frames = absl::GetFlag(FLAGS_frames);
    options.html = absl::GetFlag(FLAGS_html);
    options.family_params = repeated.params;
    return cli::Rollout(client, options);
  }
  if (command == "family") {
    cli::FamilyQueryOptions options;
    options.checkpoint = absl::GetFlag(FLAGS_checkpoint);
    options.upload = absl::GetFlag(FLAGS_upload);
    options.params = repeated.params;
    options.nearest_elites = absl::GetFlag(FLAGS_nearest_elites);
    options.out = absl::GetFlag(FLAGS_out);
    return cli::QueryFamily(client, options);
  }
  cli::SimulateOptions options;
  options.num_envs = absl::GetFlag(FLAGS_envs);
  options.steps = absl::GetFlag(FLAGS_steps);
  options.random_actions = absl::GetFlag(FLAGS_actions) == "random";
  options.seed = absl::GetFlag(FLAGS_seed);
  options.part_layout = absl::GetFlag(FLAGS_part_layout);
  options.clips = clips;
  return cli::Simulate(client, options);
}

// What is wrong with the command line of `command` (its operands and flags), or "" when nothing is.
std::string CommandLineError(const std::string& command, const std::vector<std::string>& operands,
                             const RepeatedFlags& repeated) {
  static const char* const kCommands[] = {"describe", "motions", "stats", "add-motions", "rollout", "simulate",
                                          "skills", "compose", "family"};
  if (std::find(std::begin(kCommands), std::end(kCommands), command) == std::end(kCommands)) {
    return absl::StrCat("unknown command '", command, "'");
  }
  if (command == "add-motions") {
    if (operands.empty()) return "add-motions: give at least one FILE";
  } else if (!operands.empty()) {
    return absl::StrCat(command, ": unexpected argument '", operands[0], "'");
  }
  const double timeout = absl::GetFlag(FLAGS_timeout_s);
  if (!(timeout > 0) || timeout > 86400) return "--timeout_s must be in (0, 86400]";
  // gRPC would quietly use port 443 for a bare host name.
  if (absl::GetFlag(FLAGS_server).find(':') == std::string::npos) {
    return absl::StrCat("--server: '", absl::GetFlag(FLAGS_server), "' has no port; give host:port");
  }
  if (command == "rollout") {
    if (absl::GetFlag(FLAGS_checkpoint).empty()) return "rollout: --checkpoint is required";
    if (absl::GetFlag(FLAGS_frames) && absl::GetFlag(FLAGS_out).empty()) {
      return "rollout: --frames needs --out (frames go to the JSON file)";
    }
  }
  if (command == "family") {
    if (absl::GetFlag(FLAGS_checkpoint).empty()) return "family: --checkpoint is required";
    if (absl::GetFlag(FLAGS_nearest_elites) < 0 || absl::GetFlag(FLAGS_nearest_elites) > 64) {
      return "--nearest_elites must be in [0, 64]";
    }
  }
  if (!repeated.params.empty() && command != "rollout" && command != "family") {
    return absl::StrCat(command, ": --param applies to rollout and family only");
  }
  if (command == "skills" || command == "compose") {
    if (absl::GetFlag(FLAGS_checkpoint).empty()) return command + ": --checkpoint is required";
    if (absl::GetFlag(FLAGS_out).empty()) return command + ": --out DIR is required";
    if (absl::GetFlag(FLAGS_max_steps) < 0) return "--max_steps must be >= 0";
  }
  if (command == "compose") {
    if (absl::GetFlag(FLAGS_base).empty() || absl::GetFlag(FLAGS_source).empty()) {
      return "compose: --base and --source are required";
    }
    if (absl::GetFlag(FLAGS_parts).empty()) return "compose: --parts is required (e.g. --parts R_Arm,L_Arm)";
  }
  if (command == "simulate") {
    if (absl::GetFlag(FLAGS_envs) < 1) return "--envs must be >= 1";
    if (absl::GetFlag(FLAGS_steps) < 1) return "--steps must be >= 1";
    const std::string actions = absl::GetFlag(FLAGS_actions);
    if (actions != "zero" && actions != "random") {
      return absl::StrCat("--actions must be zero or random, not '", actions, "'");
    }
  }
  return "";
}

int Main(int argc, char** argv) {
  absl::SetProgramUsageMessage(kUsage);
  // --help lists this file's flags (absl's default looks for <program name>.cc).
  absl::FlagsUsageConfig usage_config;
  usage_config.contains_help_flags = [](absl::string_view path) {
    return absl::EndsWith(path, "modskill_client_main.cc");
  };
  usage_config.contains_helpshort_flags = usage_config.contains_help_flags;
  usage_config.version_string = [] { return std::string("modskill-client 0.1.0\n"); };
  absl::SetFlagsUsageConfig(usage_config);
  RepeatedFlags repeated;
  if (std::string error; !PrescanFlags(argc, argv, &repeated, &error)) return Usage(error);
  std::vector<char*> args = absl::ParseCommandLine(argc, argv);
  if (repeated.clips.empty()) repeated.clips = absl::GetFlag(FLAGS_clip);  // e.g. from a --flagfile
  if (repeated.params.empty()) {
    std::string error;
    for (const std::string& entry : absl::GetFlag(FLAGS_param)) {
      if (!ParseParams(entry, &repeated.params, &error)) return Usage(error);
    }
  }
  if (args.size() < 2) return Usage("no command given");
  const std::string command = args[1];
  const std::vector<std::string> operands(args.begin() + 2, args.end());

  if (std::string error = CommandLineError(command, operands, repeated); !error.empty()) return Usage(error);

  auto client = Connect();
  if (!client.ok()) {
    if (client.status().code() == absl::StatusCode::kUnavailable) {
      return cli::Fail(absl::StrCat(client.status().message(),
                               " (is modskill-server running there and reachable? a TLS server needs --tls_ca, "
                               "and --tls_server_name must match its certificate; a plain server needs no --tls_ca)"));
    }
    return cli::Fail(client.status());
  }
  return RunCommand(**client, command, operands, repeated);
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) { return modskill::Main(argc, argv); }
