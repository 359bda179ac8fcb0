// modskill-server: serves humanoid simulation sessions, rollouts and the motion library over
// gRPC (see proto/modskill/v1/modskill.proto).
#include <pthread.h>
#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/log.h"
#include "common/policy/policy_checkpoint.h"
#include "server/core/curriculum/adaptive_sampler.h"
#include "server/core/curriculum/session_motion_set.h"
#include "server/core/motion/resource_limits.h"
#include "server/core/util/data_paths.h"
#include "server/service/server_runner.h"

ABSL_FLAG(int, port, 50051, "TCP port (0: any free port, printed at start)");
ABSL_FLAG(std::string, bind, "127.0.0.1", "address to listen on (0.0.0.0 for every interface)");
ABSL_FLAG(int, threads, 2, "worker threads stepping each session's envs");
ABSL_FLAG(std::string, motions, "", "directory of .msclip files (default: the shipped library)");
ABSL_FLAG(int, max_sessions, 8, "simultaneous simulation sessions");
ABSL_FLAG(int, max_envs_per_session, 4096, "envs one session may open");
ABSL_FLAG(int, max_upload_mb, 64, "bytes one AddMotions call may upload, in MiB");
ABSL_FLAG(int, max_message_mb, 512, "largest gRPC message, in MiB");
ABSL_FLAG(std::string, auth_token_file, "", "file holding a token; every call then needs 'authorization: Bearer <token>'");
ABSL_FLAG(std::string, tls_cert, "", "PEM certificate chain (with --tls_key: serve TLS)");
ABSL_FLAG(std::string, tls_key, "", "PEM private key");
ABSL_FLAG(std::string, pd_mode, "position_implicit",
          "position_implicit or stable_pd (motor-skill family sessions always run stable_pd)");
ABSL_FLAG(double, pd_gain_scale, 1.0,
          "multiplies every hinge's PD gains kp and kd (PHC's), in (0, 100]; a policy runs best at the gains it "
          "was trained with");
ABSL_FLAG(int, substeps, 4,
          "physics steps per 30 Hz control step, in [1, 100] (4: 120 Hz physics; 2: PHC's 60 Hz); a policy runs "
          "best at the rate it was trained at");
ABSL_FLAG(bool, damp_to_reference_rate, false,
          "residual PD targets lead the reference by kd/kp x its hinge rate, so the servos damp toward the "
          "reference's velocity instead of toward rest (not in motor-skill family sessions)");
ABSL_FLAG(std::string, sampling, "failure_count",
          "how sessions pick clips from ReportFailures: failure_count (PHC: probability ~ recent failures), "
          "decay_on_success (ProtoMotions: weight x0.999 per success, 1 per failure), failure_rate "
          "(failures per simulated step, fair to long clips) or uniform");
ABSL_FLAG(bool, no_adaptive, false, "ablation: uniform clip sampling whatever --sampling says");
ABSL_FLAG(double, sampling_floor, modskill::kDefaultSamplingFloor,
          "share of the probability spread uniformly: every clip keeps >= sampling_floor / clips (0 .. 1)");
ABSL_FLAG(bool, no_generative, false, "ablation: never generate variants of failed clips");
ABSL_FLAG(int, variants_per_failure, 3, "clips generated per round for a failed clip (N in ModSkill), 1 .. 64");
ABSL_FLAG(int, max_generated_clips, -1,
          "generated clips a session keeps at most (-1: as many as its original clips); the least sampled "
          "(then oldest) leave first");
ABSL_FLAG(int, failures_per_round, 200,
          "terminated episodes a clip collects between two of its generation rounds (the paper: a round every 2e8 steps)");
ABSL_FLAG(std::string, generator, "",
          "host:port of an external MotionGenerator service (e.g. client/python/examples/"
          "motion_generator_service.py); empty: the built-in generator only");
ABSL_FLAG(int, generator_timeout_ms, 10000, "deadline of one external generator call");
ABSL_FLAG(int, max_clip_frames, modskill::ResourceLimits{}.max_clip_frames,
          "most frames one clip may hold, at its own rate or resampled (uploads, library, generated)");
ABSL_FLAG(int64_t, max_decompressed_bytes, modskill::ResourceLimits{}.max_decompressed_bytes,
          "most bytes an uploaded .npz may inflate to, over all its members");
ABSL_FLAG(int, max_name_length, modskill::ResourceLimits{}.max_name_length, "most characters in a clip name");
ABSL_FLAG(std::vector<std::string>, checkpoint_dir, {},
          "directories (comma-separated) whose policy files a Rollout may name by checkpoint_path; "
          "none (the default): clients send checkpoint_bytes");
ABSL_FLAG(int64_t, max_saved_generated_clips, 10000, "clip files --save_generated writes over the server's life");
ABSL_FLAG(int, max_library_clips, 10000, "clips the library may hold, shipped and uploaded with AddMotions");
ABSL_FLAG(std::string, save_generated, "",
          "directory: also write every generated clip that joins a session as <session>/<name>.msclip");

namespace modskill {
namespace {

// Every flag check fails with a status whose message is what the server prints.
absl::Status Invalid(const std::string& message) { return absl::InvalidArgumentError(message); }

// The per-clip and per-upload limits of every importer, set before the library loads and any
// thread starts.
absl::Status ApplyResourceLimits() {
  ResourceLimits limits;
  limits.max_clip_frames = absl::GetFlag(FLAGS_max_clip_frames);
  limits.max_decompressed_bytes = absl::GetFlag(FLAGS_max_decompressed_bytes);
  limits.max_npz_member_bytes = std::min(limits.max_npz_member_bytes, limits.max_decompressed_bytes);
  limits.max_name_length = absl::GetFlag(FLAGS_max_name_length);
  if (limits.max_clip_frames < 2) return Invalid("--max_clip_frames must be >= 2");
  if (limits.max_decompressed_bytes < 1) return Invalid("--max_decompressed_bytes must be >= 1");
  if (limits.max_name_length < 1) return Invalid("--max_name_length must be >= 1");
  SetDefaultResourceLimits(limits);
  return absl::OkStatus();
}

// Where the server listens and how much it takes on: messages, sessions, envs, uploads, physics.
absl::Status ReadNetworkAndCapacity(ServerOptions& options) {
  options.bind = absl::GetFlag(FLAGS_bind);
  options.port = absl::GetFlag(FLAGS_port);
  options.tls_cert_file = absl::GetFlag(FLAGS_tls_cert);
  options.tls_key_file = absl::GetFlag(FLAGS_tls_key);
  if (absl::GetFlag(FLAGS_max_message_mb) < 1) return Invalid("--max_message_mb must be >= 1");
  options.max_message_bytes = int64_t{absl::GetFlag(FLAGS_max_message_mb)} << 20;
  options.service.threads_per_session = absl::GetFlag(FLAGS_threads);
  options.service.max_sessions = absl::GetFlag(FLAGS_max_sessions);
  options.service.max_envs_per_session = absl::GetFlag(FLAGS_max_envs_per_session);
  options.service.max_upload_bytes = int64_t{absl::GetFlag(FLAGS_max_upload_mb)} << 20;
  if (options.service.threads_per_session < 1) return Invalid("--threads must be >= 1");
  if (options.service.max_sessions < 1) return Invalid("--max_sessions must be >= 1");
  if (options.service.max_envs_per_session < 1) return Invalid("--max_envs_per_session must be >= 1");
  auto pd_mode = ParsePdMode(absl::GetFlag(FLAGS_pd_mode));
  if (!pd_mode.ok()) return Invalid(std::string(pd_mode.status().message()));
  options.service.physics.pd_mode = *pd_mode;
  options.service.physics.pd_gain_scale = absl::GetFlag(FLAGS_pd_gain_scale);
  options.service.physics.damp_to_reference_rate = absl::GetFlag(FLAGS_damp_to_reference_rate);
  options.service.physics.substeps = absl::GetFlag(FLAGS_substeps);
  for (const absl::Status& status :
       {ValidateSubsteps(options.service.physics.substeps, "--substeps"),
        ValidatePdGainScale(options.service.physics.pd_gain_scale, "--pd_gain_scale")}) {
    if (!status.ok()) return Invalid(std::string(status.message()));
  }
  return absl::OkStatus();
}

// The curriculum: how sessions sample clips and when and how they generate variants.
absl::Status ReadCurriculum(ServiceOptions& service) {
  auto sampling = ParseSamplingScheme(absl::GetFlag(FLAGS_sampling));
  if (!sampling.ok()) return Invalid(absl::StrCat("--", sampling.status().message()));
  service.sampling = absl::GetFlag(FLAGS_no_adaptive) ? SamplingScheme::kUniform : *sampling;
  service.sampling_floor = absl::GetFlag(FLAGS_sampling_floor);
  if (absl::Status status = ValidateSamplingParameters(service.sampling_floor, kDefaultSamplingDecay,
                                                       "--sampling_floor");
      !status.ok()) {
    return Invalid(std::string(status.message()));
  }
  GenerationOptions& generation = service.generation;
  generation.enabled = !absl::GetFlag(FLAGS_no_generative);
  generation.variants_per_round = absl::GetFlag(FLAGS_variants_per_failure);
  generation.max_generated_clips = absl::GetFlag(FLAGS_max_generated_clips);
  generation.failures_per_round = absl::GetFlag(FLAGS_failures_per_round);
  if (absl::Status status = ValidateGenerationOptions(generation); !status.ok()) {
    return Invalid(std::string(status.message()));
  }
  service.generator_address = absl::GetFlag(FLAGS_generator);
  if (absl::GetFlag(FLAGS_generator_timeout_ms) < 1) return Invalid("--generator_timeout_ms must be >= 1");
  service.generator_timeout = absl::Milliseconds(absl::GetFlag(FLAGS_generator_timeout_ms));
  service.generated_clip_dir = absl::GetFlag(FLAGS_save_generated);
  service.max_saved_generated_clips = absl::GetFlag(FLAGS_max_saved_generated_clips);
  service.max_library_clips = absl::GetFlag(FLAGS_max_library_clips);
  if (service.max_saved_generated_clips < 0) return Invalid("--max_saved_generated_clips must be >= 0");
  if (service.max_library_clips < 1) return Invalid("--max_library_clips must be >= 1");
  return absl::OkStatus();
}

// Who may call and which checkpoint files a Rollout may name.
absl::Status ReadAccess(ServiceOptions& service) {
  for (const std::string& directory : absl::GetFlag(FLAGS_checkpoint_dir)) {
    std::error_code error;
    if (!std::filesystem::is_directory(directory, error)) {
      return Invalid(absl::StrCat("--checkpoint_dir: ", directory, " is not a directory"));
    }
    service.checkpoint_dirs.push_back(directory);
  }
  if (!absl::GetFlag(FLAGS_auth_token_file).empty()) {
    auto token = ReadFileToString(absl::GetFlag(FLAGS_auth_token_file), 4096);
    if (!token.ok()) return Invalid(absl::StrCat("--auth_token_file: ", token.status().message()));
    service.auth_token = std::string(absl::StripAsciiWhitespace(*token));
    if (service.auth_token.empty()) return Invalid("--auth_token_file: the file is empty");
  }
  return absl::OkStatus();
}

// The one line that says the server is up and how it is configured.
void LogListening(const ServerOptions& options, int port, int num_clips, const std::string& motion_dir) {
  const GenerationOptions& generation = options.service.generation;
  const PhysicsOptions& physics = options.service.physics;
  LogLine("modskill-server listening on %s:%d (%s%s), %d clips from %s, %s PD at %g x PHC's gains%s, %g Hz physics, %d threads "
          "per session, %s sampling (floor %g), generative resampling %s",
          options.bind, port, options.tls_cert_file.empty() ? "insecure" : "TLS",
          options.service.auth_token.empty() ? "" : ", token auth", num_clips, motion_dir,
          PdModeName(physics.pd_mode), physics.pd_gain_scale,
          physics.damp_to_reference_rate ? " damped toward the reference's rate" : "", 1.0 / physics.physics_dt(),
          options.service.threads_per_session, SamplingSchemeName(options.service.sampling),
          options.service.sampling_floor,
          !generation.enabled ? std::string("off")
          : absl::StrCat(generation.variants_per_round, " variants per round, cap ",
                         generation.max_generated_clips < 0 ? std::string("= the session's clips")
                                                            : absl::StrCat(generation.max_generated_clips),
                         options.service.generator_address.empty()
                             ? std::string(", built-in generator")
                             : absl::StrCat(", generator ", options.service.generator_address)));
}

int Fail(const std::string& message) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return 2;
}

int Main() {
  if (absl::Status status = ApplyResourceLimits(); !status.ok()) return Fail(std::string(status.message()));
  ServerOptions options;
  if (absl::Status status = ReadNetworkAndCapacity(options); !status.ok()) return Fail(std::string(status.message()));
  if (absl::Status status = ReadCurriculum(options.service); !status.ok()) return Fail(std::string(status.message()));
  if (absl::Status status = ReadAccess(options.service); !status.ok()) return Fail(std::string(status.message()));
  auto spec = HumanoidSpec::LoadDefault();
  if (!spec.ok()) return Fail(std::string(spec.status().message()));
  const std::string motion_dir = absl::GetFlag(FLAGS_motions).empty() ? DataPath("motions") : absl::GetFlag(FLAGS_motions);
  auto library = MotionLibrary::LoadDirectory(motion_dir, *spec);
  if (!library.ok()) return Fail(absl::StrCat("--motions: ", library.status().message()));
  // One intra-op thread: rollout batches are small and sessions already use --threads.
  SetTorchThreads(1);

  // SIGINT/SIGTERM are taken by a dedicated wait below, not by whichever thread they hit.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const int num_clips = library->size();
  auto server = StartServer(options, std::make_shared<const MotionLibrary>(*std::move(library)));
  if (!server.ok()) return Fail(std::string(server.status().message()));
  LogListening(options, (*server)->port(), num_clips, motion_dir);
  std::fflush(stderr);
  int signal_number = 0;
  sigwait(&signals, &signal_number);
  LogLine("%s: draining (running calls get 5 s), then stopping", signal_number == SIGINT ? "SIGINT" : "SIGTERM");
  (*server)->Shutdown(absl::Seconds(5));
  (*server)->Wait();
  LogLine("stopped");
  return 0;
}

}  // namespace
}  // namespace modskill

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("serves humanoid simulation sessions over gRPC");
  absl::ParseCommandLine(argc, argv);
  return modskill::Main();
}
