// modskill-learner: trains a ModSkill policy against one or many simulation servers, or
// evaluates a trained one (--eval).
//
//   modskill-learner --servers host:port|dns:///name:port|file:///path[,...] --run_dir DIR --preset small|paper --iterations N
//   modskill-learner --eval --checkpoint DIR/policy.pt --servers host:port [--clips a,b] [--eval_out DIR]
//
// Skill reuse: --task steer|reach|strike|vr_tracking --skills TRACKER/policy.pt trains a task
// policy over the tracker's frozen part controllers; --eval --task ... evaluates one, with
// --task_baselines beside random and constant z.
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/log.h"
#include "common/policy/policy_checkpoint.h"
#include "common/viewer/viewer_wire.h"
#include "common/wire/policy_enums.h"
#include "learner/best_policy_keeper.h"
#include "learner/evaluation.h"
#include "learner/policy_import.h"
#include "learner/server_discovery.h"
#include "learner/skill_library.h"
#include "learner/task_checkpoint_evaluation.h"
#include "learner/task_evaluation.h"
#include "learner/tensorboard_writer.h"
#include "learner/tools/family_command.h"
#include "learner/tools/iteration_report.h"
#include "learner/trainer.h"

ABSL_FLAG(std::vector<std::string>, servers, {},
          "simulation servers, comma-separated: host:port, dns:///name:port (every address behind the name, "
          "re-resolved each iteration), file:///path (one host:port per line, re-read when it changes)");
ABSL_FLAG(std::string, run_dir, "", "where checkpoints, the exported policy and logs go");
ABSL_FLAG(std::string, preset, "small", "network and optimizer sizes: small (2-core CPU) or paper");
ABSL_FLAG(int, iterations, 100, "PPO iterations to run (after those of a resumed run)");
ABSL_FLAG(double, time_budget_min, 0, "stop after this many minutes of training (0: no limit)");
ABSL_FLAG(int, envs_per_server, 0, "envs on each server (0: the preset's, 256 for small)");
ABSL_FLAG(int, sessions_per_server, 2, "sessions per server; 2 overlaps simulation with inference");
ABSL_FLAG(std::string, part_layout, "5part", "body-part layout: 5part, 3part, 2part or 1part");
ABSL_FLAG(std::vector<std::string>, motions, {}, "clips to train on (default: the server's library)");
ABSL_FLAG(bool, whole_body, false, "ablation: one controller for the whole body");
ABSL_FLAG(bool, no_attention, false, "ablation: no attention across parts");
ABSL_FLAG(std::string, controller_input, "part_obs",
          "what each part's controller reads beside z: part_obs (the part's whole observation) or proprioception "
          "(the reference reaches it only through z, so that high-level task policies can reuse the controllers)");
ABSL_FLAG(std::string, task, "tracking",
          "tracking, or a task env the server lists (steer, reach, strike, vr_tracking): trains a high-level policy "
          "that drives the frozen part controllers of --skills");
ABSL_FLAG(std::string, skills, "",
          "--task: a tracker's exported policy.pt, trained with --controller_input proprioception");
ABSL_FLAG(std::string, init_from, "",
          "tracking: start from this tracker's exported policy.pt (attention, controllers, observation statistics)");
ABSL_FLAG(std::vector<std::string>, train_parts, {},
          "with --init_from: only these parts' controllers and attention maps train (e.g. R_Arm,L_Arm); the other "
          "parts and the observation statistics stay frozen (default: every part trains)");
ABSL_FLAG(bool, train_attention, true,
          "with --train_parts: their attention maps train too; false: their controllers alone, so every part's z "
          "stays the tracker's");
ABSL_FLAG(bool, fresh_parts, false,
          "with --train_parts: those parts start from fresh weights (a part new to the tracker: its controller, and "
          "its attention maps when they train), not from the tracker's");
ABSL_FLAG(bool, frozen_parts_act_on_mean, false,
          "with --train_parts: the frozen parts act on their means (no exploration noise, no share in PPO's ratios), "
          "as they will in evaluation");
ABSL_FLAG(std::vector<std::string>, reward_parts, {},
          "tracking: the imitation reward averages over these parts' bodies only (e.g. the --train_parts), so the "
          "frozen parts' errors do not drown the retrained parts' signal (default: every body)");
ABSL_FLAG(bool, reward_relative_to_root, false,
          "tracking: the imitation reward compares the rewarded bodies in the root's frame, so the root's drift "
          "(set by the frozen parts) stays out of the --reward_parts' reward");
ABSL_FLAG(bool, loop_clips, false,
          "tracking: clips loop (on at frame 1, carried by their own displacement) and episodes run 300 steps, so "
          "the skills learn to go on as a task's looping base motion asks");
ABSL_FLAG(bool, anchor_reference, false,
          "tracking: each step the reference is carried onto the character's root and heading, as a task's base "
          "motion is, so the skills learn to go on from where they are instead of winning back drift");
ABSL_FLAG(bool, anchor_position_only, false,
          "with --anchor_reference: carry the reference onto the character's root position only; it keeps the "
          "clip's heading, so the skills learn to win back a heading error and follow a steered base motion "
          "(--task_steering_rate)");
ABSL_FLAG(int32_t, reference_frames, -1,
          "tracking: how many upcoming reference frames each body observes (the next one and N - 1 after it, "
          "MimicKit's tar_obs_steps), in [1, 8]; not with --loop_clips or --anchor_reference. Default 1; a --resume "
          "keeps its checkpoint's");
ABSL_FLAG(double, task_log_std, -2.9, "--task: fixed log standard deviation of the task policy in z space");
ABSL_FLAG(bool, task_skill_prior, true,
          "--task steer|reach|strike: z = normalize(z_prior + task head), z_prior from the tracker's frozen attention on "
          "the anchored base motion (false: z = normalize(task head), the paper's high level)");
ABSL_FLAG(std::vector<std::string>, task_parts, {},
          "--task steer|reach|strike: the parts whose z the task head displaces, e.g. R_Arm for reach; the others play "
          "the skill prior's z without exploration noise (default: every part, the paper's high level)");
ABSL_FLAG(std::string, task_teacher, "",
          "--task reach: a teacher table of held reach poses (bench/reach_teacher.py); the update pulls the head's "
          "mean z toward the z of the pose nearest each goal (behaviour cloning); with --eval, a row for the teacher "
          "itself");
ABSL_FLAG(double, task_teacher_weight, 1.0, "--task_teacher: weight of its loss beside PPO's, in [0, 100]");
ABSL_FLAG(int64_t, task_teacher_steps, 0,
          "--task_teacher: env steps over which its weight falls linearly to 0 (0: held for the whole run)");
ABSL_FLAG(std::vector<std::string>, task_hidden, {},
          "--task: hidden sizes of the task head, e.g. 2048,1024,512 (default: the preset's; small 256,128)");
ABSL_FLAG(std::vector<std::string>, controller_hidden, {},
          "hidden sizes of each part's controller, e.g. 512,256 (default: the preset's; small 256,128, paper "
          "2048,1536,1024,512); a --resume repeats the run's own");
ABSL_FLAG(std::vector<std::string>, critic_hidden, {},
          "hidden sizes of the critic, e.g. 512,256 (default: the preset's; small 256,128)");
ABSL_FLAG(double, task_min_speed, 0, "steer: lowest target speed, m/s (0: the server's default, 0.5)");
ABSL_FLAG(double, task_max_speed, 0, "steer: highest target speed, m/s (0: the server's default, 3)");
ABSL_FLAG(double, task_min_goal_interval_s, 0, "steer, reach: shortest time between goals, s (0: default 2)");
ABSL_FLAG(double, task_max_goal_interval_s, 0, "steer, reach: longest time between goals, s (0: default 5)");
ABSL_FLAG(double, task_reach_box_size, 0, "reach: edge of the box targets are drawn in, m (0: the paper's 2)");
ABSL_FLAG(std::vector<std::string>, task_reach_center, {},
          "reach: the box's centre in the heading frame, forward,left,height in m (default: the paper's 0,0,1)");
ABSL_FLAG(double, task_steering_rate, 0,
          "steer, reach, strike: the base motion turns toward the goal at up to this rate, deg/s (0: straight on, "
          "the paper's); --eval --task takes it too");
ABSL_FLAG(bool, task_baselines, false,
          "--eval --task: also drive the skills with a random unit z per part each step and with the task "
          "policy's mean z");
ABSL_FLAG(int, eval_episodes, 32, "--eval --task: episodes per run (one per env)");
ABSL_FLAG(int, horizon, 32, "steps per env per iteration");
ABSL_FLAG(double, gamma, -1,
          "discount factor, in (0, 1] (-1: the preset's: 0.95 for small's tracking runs, DeepMimic's; else 0.99, "
          "PHC's; on --resume the run's)");
ABSL_FLAG(double, lambda, -1, "GAE's lambda, in [0, 1] (-1: the preset's 0.95; on --resume the run's)");
ABSL_FLAG(int, epochs, 0, "PPO epochs per iteration (0: the preset's)");
ABSL_FLAG(int, minibatch_size, 0, "PPO minibatch (0: the preset's)");
ABSL_FLAG(int, discriminator_epochs, 0, "AMP discriminator epochs per iteration (0: the preset's)");
ABSL_FLAG(int, amp_frames, -1,
          "frames of the server's AMP history the discriminator reads, newest first (0: all of them; -1: the "
          "preset's, or the resumed checkpoint's)");
ABSL_FLAG(double, learning_rate, 0, "Adam learning rate (0: the preset's)");
ABSL_FLAG(int64_t, learning_rate_decay_steps, 0,
          "decay --learning_rate linearly to --learning_rate_floor x it over this many env steps (0: constant)");
ABSL_FLAG(double, learning_rate_floor, 0.1, "the decayed learning rate's final fraction of --learning_rate, in (0, 1]");
ABSL_FLAG(double, critic_learning_rate, -1,
          "the critic's own Adam learning rate, decayed with --learning_rate (0: the critic uses --learning_rate; "
          "-1: the preset's, 1e-3 for small's tracking runs, else 0, or on --resume the checkpoint's)");
ABSL_FLAG(double, log_std, 0, "fixed log standard deviation of the Gaussian policy (0: the preset's)");
ABSL_FLAG(double, amp_reward_weight, -1,
          "weight of the AMP style reward (task: 1 - this); -1: tracking runs the preset's (small 0.2, paper 0.5), "
          "task runs 0.5");
ABSL_FLAG(double, energy_weight, 1,
          "the sessions' energy penalty as a multiple of the paper's (SessionConfig.energy_weight; 1: the paper's; 0: off, so that "
          "no step of a goal task is negative and falling never pays)");
ABSL_FLAG(std::string, imitation_kernels, "",
          "the imitation reward's kernels, e.g. pos=400,rot=20 (terms pos, rot, vel, ang_vel; each term is "
          "w exp(-k x its mean squared error); unnamed terms keep PHC's 100, 10, 0.1, 0.1)");
ABSL_FLAG(int, noise_hold_steps, 1,
          "each env keeps its exploration noise for this many control steps on average (geometric, redrawn when its "
          "episode ends); 1: fresh every step. For task heads, whose per-step z noise the skills average away");
ABSL_FLAG(std::string, action_mode, "", "absolute (PD target = offset + scale * a, the paper's) or residual "
          "(the reference pose + residual_scale * scale * a); default: the preset's (small: residual, paper: absolute)");
ABSL_FLAG(double, residual_scale, 0.5, "residual mode: share of each hinge's action scale an action of 1 moves");
ABSL_FLAG(double, termination_distance, 0.25, "training: an episode fails when a watched body is farther (m)");
ABSL_FLAG(std::string, termination_bodies, "",
          "bodies training termination watches: all or no_feet (PHC); default: the preset's (small: no_feet, paper: all)");
ABSL_FLAG(std::string, termination_curriculum, "",
          "START:END (m): start loose and tighten toward END as episodes reach their clip's end");
ABSL_FLAG(int, update_threads, 2, "torch threads for the updates, while the servers wait (0: as --threads)");
ABSL_FLAG(bool, normalize_value, false,
          "the critic predicts returns normalized by their running mean and std (rl_games' normalize_value); a "
          "resumed run keeps its checkpoint's setting");
ABSL_FLAG(bool, collect_during_update, false,
          "collect the next batch while the update runs, with the weights from before it (policy lag 1)");
ABSL_FLAG(uint64_t, seed, 1, "random seed");
ABSL_FLAG(int, checkpoint_every, 10, "iterations between checkpoints");
ABSL_FLAG(int, report_every, 5, "iterations between failure reports to the servers' samplers (0: never)");
ABSL_FLAG(bool, resume, false, "continue the run in --run_dir from its checkpoint");
ABSL_FLAG(double, server_timeout_s, 120, "exit when no server answers for this long");
ABSL_FLAG(int, threads, 1, "torch threads for inference and updates (the servers need the other cores)");
ABSL_FLAG(std::string, auth_token_file, "", "bearer token for the servers");
ABSL_FLAG(std::string, tls_ca, "", "PEM roots: connect with TLS");
ABSL_FLAG(bool, eval, false, "evaluate --checkpoint instead of training");
ABSL_FLAG(std::string, checkpoint, "", "--eval: the exported TorchScript policy (run_dir/policy.pt)");
ABSL_FLAG(std::vector<std::string>, clips, {}, "--eval: clips to evaluate (default: all)");
ABSL_FLAG(std::string, eval_out, "", "--eval: directory for eval.json and eval.md (default: the checkpoint's)");
ABSL_FLAG(bool, baseline, false,
          "--eval: evaluate the open-loop reference (PD targets = the reference pose) instead of --checkpoint");
ABSL_FLAG(int, world_size, 1,
          "data-parallel learners: how many learners train one policy together, each on its own --servers "
          "(gradients averaged every minibatch); 1: this learner alone");
ABSL_FLAG(int, rank, 0, "data-parallel learners: this learner's rank in [0, --world_size); rank 0 writes the run");
ABSL_FLAG(std::string, rendezvous, "",
          "data-parallel learners: rank 0's host:port (rank 0 listens on the port, every rank connects)");
ABSL_FLAG(double, rendezvous_timeout_s, 60, "data-parallel learners: how long ranks wait for each other at startup");
ABSL_FLAG(double, collective_timeout_s, 300,
          "data-parallel learners: how long a rank waits in one collective for the others before it stops");
ABSL_FLAG(int, keep_best_every, 0,
          "tracking runs: every N iterations evaluate the policy on the run's clips with the paper's protocol "
          "(the first server's Rollout) and keep the best so far as run_dir/policy_best.pt (0: never)");
ABSL_FLAG(std::vector<std::string>, milestones, {},
          "env step counts (e.g. 1e6,5e6) at which the policy is also exported as policy_at_<N>M.pt");

namespace modskill::learner {
namespace {

std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }

int Fail(const std::string& message, int code = 1) {
  std::fprintf(stderr, "error: %s\n", message.c_str());
  return code;
}

// eval.html's recorder. A page that cannot be made (a server without geometry, no three.js) is
// a warning: the figures still count.
std::optional<RolloutViewerRecorder> EvalPageRecorder(SimulationClient& client, const v1::EnvSpec& spec) {
  auto motions = client.ListMotions();
  absl::StatusOr<RolloutViewerRecorder> recorder =
      motions.ok() ? PrepareRolloutPage(spec, *motions) : absl::StatusOr<RolloutViewerRecorder>(motions.status());
  if (recorder.ok()) return *std::move(recorder);
  LogLine("warning: no eval.html: %s", recorder.status().message());
  return std::nullopt;
}

void WriteEvalPage(RolloutViewerRecorder& page, std::string title, const std::string& path) {
  absl::StatusOr<size_t> clips = WriteRolloutPage(page, std::move(title), path);
  if (clips.ok()) {
    LogLine("wrote %s (the policy beside its reference, %d clips)", path, static_cast<int>(*clips));
  } else {
    LogLine("warning: no eval.html: %s", clips.status().message());
  }
}

// --eval_out, or the checkpoint's directory.
// --eval talks to the first of --servers.
absl::StatusOr<std::unique_ptr<SimulationClient>> ConnectToFirstServer(const std::string& token) {
  absl::StatusOr<std::string> first = FirstServerTarget(absl::GetFlag(FLAGS_servers));
  if (!first.ok()) return first.status();
  ClientOptions options;
  options.server = *first;
  options.token = token;
  options.tls_ca_file = absl::GetFlag(FLAGS_tls_ca);
  return SimulationClient::Connect(options);
}

std::string EvalOutDir(const std::string& checkpoint) {
  std::string out_dir = absl::GetFlag(FLAGS_eval_out);
  if (out_dir.empty()) out_dir = std::filesystem::path(checkpoint).parent_path().string();
  return out_dir.empty() ? "." : out_dir;
}

// Prints `markdown` and writes it and `json` as eval.md and eval.json in `out_dir`.
int WriteEvalFiles(const std::string& out_dir, const std::string& markdown, const std::string& json) {
  std::printf("%s", markdown.c_str());
  std::error_code error;
  std::filesystem::create_directories(out_dir, error);
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"eval.json", json}, {"eval.md", markdown}}) {
    if (absl::Status status = WriteFileAtomically(out_dir + "/" + name, text); !status.ok()) {
      return Fail(std::string(status.message()));
    }
  }
  LogLine("wrote %s/eval.json and %s/eval.md", out_dir, out_dir);
  return 0;
}

int RunEvaluation(const std::string& token) {
  const std::string checkpoint = absl::GetFlag(FLAGS_checkpoint);
  const bool baseline_only = absl::GetFlag(FLAGS_baseline);
  if (checkpoint.empty() == !baseline_only) {
    return Fail("--eval needs --checkpoint (a run's policy.pt) or --baseline, not both", 2);
  }
  if (absl::GetFlag(FLAGS_servers).empty()) return Fail("--eval needs --servers", 2);
  auto client = ConnectToFirstServer(token);
  if (!client.ok()) return Fail(std::string(client.status().message()));
  auto spec = (*client)->Describe();
  if (!spec.ok()) return Fail(std::string(spec.status().message()));
  auto reference_policy = OpenLoopReferencePolicy(*spec);
  if (!reference_policy.ok()) return Fail(std::string(reference_policy.status().message()));
  const std::vector<std::string> clips = absl::GetFlag(FLAGS_clips);
  LogLine("evaluating the open-loop reference on %s", (*client)->server());
  auto baseline = Evaluate(**client, "open-loop reference", *reference_policy, clips);
  if (!baseline.ok()) return Fail(std::string(baseline.status().message()));
  std::string markdown, json;
  std::optional<RolloutViewerRecorder> page;
  if (baseline_only) {
    markdown = baseline->ToMarkdown("open-loop reference (no learning)");
    json = baseline->ToJson();
  } else {
    auto bytes = ReadFileToString(checkpoint, kMaxPolicyFileBytes);
    if (!bytes.ok()) return Fail(absl::StrCat("--checkpoint: ", bytes.status().message()));
    LogLine("evaluating %s on %s", checkpoint, (*client)->server());
    page = EvalPageRecorder(**client, *spec);
    auto report = Evaluate(**client, checkpoint, *bytes, clips,
                           page ? [&page](const v1::RolloutFrame& frame) { page->Add(frame); }
                                : std::function<void(const v1::RolloutFrame&)>());
    if (!report.ok()) return Fail(std::string(report.status().message()));
    markdown = report->ToMarkdown("ModSkill (modskill, " + absl::GetFlag(FLAGS_preset) + ")") +
               CompareWithBaseline(*report, *baseline);
    json = report->ToJson();
  }
  const std::string out_dir = EvalOutDir(checkpoint);
  if (int failed = WriteEvalFiles(out_dir, markdown, json); failed != 0) return failed;
  if (page) WriteEvalPage(*page, absl::StrCat("evaluation of ", checkpoint), out_dir + "/eval.html");
  return 0;
}

// --task_min_speed ... --task_reach_center: the goal tasks' settings.
absl::Status TaskSettingsFromFlags(TrainerConfig* config) {
  config->task_min_speed = absl::GetFlag(FLAGS_task_min_speed);
  config->task_max_speed = absl::GetFlag(FLAGS_task_max_speed);
  config->task_min_goal_interval_s = absl::GetFlag(FLAGS_task_min_goal_interval_s);
  config->task_max_goal_interval_s = absl::GetFlag(FLAGS_task_max_goal_interval_s);
  config->task_reach_box_size = absl::GetFlag(FLAGS_task_reach_box_size);
  config->task_steering_rate = absl::GetFlag(FLAGS_task_steering_rate);
  config->task_reach_center.clear();
  for (const std::string& text : absl::GetFlag(FLAGS_task_reach_center)) {
    double value = 0;
    if (!absl::SimpleAtod(text, &value) || !std::isfinite(value)) {
      return absl::InvalidArgumentError(
          absl::StrCat("--task_reach_center: '", text.substr(0, 32), "' is not a finite number of metres"));
    }
    config->task_reach_center.push_back(value);
  }
  return absl::OkStatus();
}

// A task policy and, with --task_baselines, the same skills under random and constant z.
absl::StatusOr<TaskEvaluationReport> EvaluateTaskFromFlags(SimulationClient& client, const std::string& checkpoint) {
  TaskCheckpointEvaluation request;
  request.checkpoint = checkpoint;
  request.task = absl::GetFlag(FLAGS_task);
  request.motions = absl::GetFlag(FLAGS_motions);
  TrainerConfig goals;
  if (absl::Status status = TaskSettingsFromFlags(&goals); !status.ok()) return status;
  WriteTaskSettings(goals, &request.task_settings);
  request.episodes = absl::GetFlag(FLAGS_eval_episodes);
  request.seed = absl::GetFlag(FLAGS_seed);
  request.baselines = absl::GetFlag(FLAGS_task_baselines);
  request.skills = absl::GetFlag(FLAGS_skills);
  request.teacher = absl::GetFlag(FLAGS_task_teacher);
  request.task_parts = absl::GetFlag(FLAGS_task_parts);
  return EvaluateTaskCheckpoint(client, request);
}

int RunTaskEvaluation(const std::string& token) {
  const std::string checkpoint = absl::GetFlag(FLAGS_checkpoint);
  if (checkpoint.empty()) return Fail("--eval --task needs --checkpoint (a task run's policy.pt)", 2);
  if (absl::GetFlag(FLAGS_baseline)) {
    return Fail("--baseline: the open-loop reference baselines a tracker; with --task use --task_baselines", 2);
  }
  if (absl::GetFlag(FLAGS_servers).empty()) return Fail("--eval needs --servers", 2);
  auto client = ConnectToFirstServer(token);
  if (!client.ok()) return Fail(std::string(client.status().message()));
  auto report = EvaluateTaskFromFlags(**client, checkpoint);
  if (!report.ok()) return Fail(std::string(report.status().message()));
  return WriteEvalFiles(EvalOutDir(checkpoint), report->ToMarkdown(), report->ToJson());
}

// --milestones: "1e6,5e6" -> sorted step counts.
absl::StatusOr<std::vector<int64_t>> ParseMilestones(const std::vector<std::string>& values) {
  std::vector<int64_t> steps;
  for (const std::string& value : values) {
    double count = 0;
    if (!absl::SimpleAtod(value, &count) || !(count >= 1 && count < 1e15)) {
      return absl::InvalidArgumentError(absl::StrCat("--milestones: '", value.substr(0, 32), "' is not a step count >= 1"));
    }
    steps.push_back(static_cast<int64_t>(count));
  }
  std::sort(steps.begin(), steps.end());
  return steps;
}

// A comma list of layer widths replaces `sizes`; empty leaves the preset's.
absl::Status HiddenSizesFromFlag(absl::string_view flag, const std::vector<std::string>& values,
                                 std::vector<int64_t>* sizes) {
  if (values.empty()) return absl::OkStatus();
  sizes->clear();
  for (const std::string& size : values) {
    int64_t value = 0;
    if (!absl::SimpleAtoi(size, &value)) {
      return absl::InvalidArgumentError(absl::StrCat(flag, ": '", size.substr(0, 32), "' is not a size"));
    }
    sizes->push_back(value);
  }
  return absl::OkStatus();
}

// --task, --skills, the task head and the task's settings.
absl::Status TaskFromFlags(TrainerConfig* config) {
  config->task = absl::GetFlag(FLAGS_task);
  config->skills = absl::GetFlag(FLAGS_skills);
  config->model.task_log_std = absl::GetFlag(FLAGS_task_log_std);
  config->model.task_skill_prior = absl::GetFlag(FLAGS_task_skill_prior);
  config->task_parts = absl::GetFlag(FLAGS_task_parts);
  config->task_teacher = absl::GetFlag(FLAGS_task_teacher);
  config->task_teacher_weight = absl::GetFlag(FLAGS_task_teacher_weight);
  config->task_teacher_steps = absl::GetFlag(FLAGS_task_teacher_steps);
  config->loop_clips = absl::GetFlag(FLAGS_loop_clips);
  config->anchor_reference = absl::GetFlag(FLAGS_anchor_reference);
  config->anchor_position_only = absl::GetFlag(FLAGS_anchor_position_only);
  config->init_from = absl::GetFlag(FLAGS_init_from);
  if (const int frames = absl::GetFlag(FLAGS_reference_frames); frames != -1) {
    config->reference_frames = frames;
    config->reference_frames_given = true;
  }
  config->train_parts = absl::GetFlag(FLAGS_train_parts);
  config->reward_parts = absl::GetFlag(FLAGS_reward_parts);
  config->reward_relative_to_root = absl::GetFlag(FLAGS_reward_relative_to_root);
  config->frozen_parts_act_on_mean = absl::GetFlag(FLAGS_frozen_parts_act_on_mean);
  config->train_attention = absl::GetFlag(FLAGS_train_attention);
  config->fresh_parts = absl::GetFlag(FLAGS_fresh_parts);
  if (absl::Status status = HiddenSizesFromFlag("--task_hidden", absl::GetFlag(FLAGS_task_hidden),
                                                 &config->model.task_hidden);
      !status.ok()) {
    return status;
  }
  return TaskSettingsFromFlags(config);
}

// The reward's weights (style, task, energy) and imitation kernels.
absl::Status RewardFromFlags(TrainerConfig* config) {
  double amp_weight = absl::GetFlag(FLAGS_amp_reward_weight);
  // The skill-reuse heads were measured at PHC's 0.5 / 0.5 (README, "Skill reuse").
  constexpr double kTaskAmpRewardWeight = 0.5;
  if (amp_weight == -1) amp_weight = config->task == "tracking" ? config->amp_reward_weight : kTaskAmpRewardWeight;
  if (!(amp_weight >= 0 && amp_weight <= 1)) {
    return absl::InvalidArgumentError(absl::StrCat("--amp_reward_weight: ", amp_weight, " must be in [0, 1]"));
  }
  config->amp_reward_weight = amp_weight;
  config->task_reward_weight = 1 - amp_weight;
  config->energy_weight = absl::GetFlag(FLAGS_energy_weight);
  auto kernels = ParseImitationKernels(absl::GetFlag(FLAGS_imitation_kernels));
  if (!kernels.ok()) return kernels.status();
  config->imitation_kernels = *kernels;
  return absl::OkStatus();
}

// The trainer's configuration from --preset and the flags that override it; every error is a
// usage error.
absl::StatusOr<TrainerConfig> ConfigFromFlags(const std::string& token) {
  auto config = TrainerConfig::ForPreset(absl::GetFlag(FLAGS_preset));
  if (!config.ok()) return absl::InvalidArgumentError(absl::StrCat("--preset: ", config.status().message()));
  config->servers = absl::GetFlag(FLAGS_servers);
  config->token = token;
  config->tls_ca_file = absl::GetFlag(FLAGS_tls_ca);
  config->run_dir = absl::GetFlag(FLAGS_run_dir);
  config->iterations = absl::GetFlag(FLAGS_iterations);
  if (absl::GetFlag(FLAGS_envs_per_server) > 0) config->envs_per_server = absl::GetFlag(FLAGS_envs_per_server);
  config->sessions_per_server = absl::GetFlag(FLAGS_sessions_per_server);
  config->part_layout = absl::GetFlag(FLAGS_part_layout);
  config->motions = absl::GetFlag(FLAGS_motions);
  config->model.whole_body = absl::GetFlag(FLAGS_whole_body);
  config->model.attention = !absl::GetFlag(FLAGS_no_attention);
  auto controller_input = ParseControllerInput(absl::GetFlag(FLAGS_controller_input));
  if (!controller_input.ok()) return controller_input.status();
  config->model.controller_input = *controller_input;
  if (absl::Status status = TaskFromFlags(&*config); !status.ok()) return status;
  for (const auto& [flag, values, sizes] :
       {std::tuple{"--controller_hidden", absl::GetFlag(FLAGS_controller_hidden), &config->model.controller_hidden},
        std::tuple{"--critic_hidden", absl::GetFlag(FLAGS_critic_hidden), &config->model.critic_hidden}}) {
    if (absl::Status status = HiddenSizesFromFlag(flag, values, sizes); !status.ok()) return status;
  }
  config->horizon = absl::GetFlag(FLAGS_horizon);
  if (absl::GetFlag(FLAGS_gamma) != -1) {
    config->gamma = absl::GetFlag(FLAGS_gamma);
    config->gamma_given = true;
  } else if (absl::GetFlag(FLAGS_preset) == "small" && IsTrackingTask(config->task)) {
    config->gamma = kSmallTrackingGamma;
  }
  if (absl::GetFlag(FLAGS_lambda) != -1) config->lambda = absl::GetFlag(FLAGS_lambda), config->lambda_given = true;
  if (absl::GetFlag(FLAGS_epochs) > 0) config->epochs = absl::GetFlag(FLAGS_epochs);
  if (absl::GetFlag(FLAGS_discriminator_epochs) > 0) config->discriminator_epochs = absl::GetFlag(FLAGS_discriminator_epochs);
  if (const int frames = absl::GetFlag(FLAGS_amp_frames); frames != -1) {
    config->model.amp_frames = frames;
    config->amp_frames_given = true;
  }
  if (absl::GetFlag(FLAGS_minibatch_size) > 0) config->minibatch_size = absl::GetFlag(FLAGS_minibatch_size);
  if (absl::GetFlag(FLAGS_learning_rate) > 0) config->learning_rate = absl::GetFlag(FLAGS_learning_rate);
  config->learning_rate_decay_steps = absl::GetFlag(FLAGS_learning_rate_decay_steps);
  config->learning_rate_floor = absl::GetFlag(FLAGS_learning_rate_floor);
  if (const double critic_rate = absl::GetFlag(FLAGS_critic_learning_rate); critic_rate != -1) {
    config->critic_learning_rate = critic_rate;
    config->critic_learning_rate_given = true;
  } else if (absl::GetFlag(FLAGS_preset) == "small" && IsTrackingTask(config->task)) {
    config->critic_learning_rate = kSmallTrackingCriticLearningRate;
  }
  if (absl::GetFlag(FLAGS_log_std) != 0) config->model.log_std = absl::GetFlag(FLAGS_log_std);
  if (absl::Status status = RewardFromFlags(&*config); !status.ok()) return status;
  config->noise_hold_steps = absl::GetFlag(FLAGS_noise_hold_steps);
  if (!absl::GetFlag(FLAGS_action_mode).empty()) config->action_mode = absl::GetFlag(FLAGS_action_mode);
  config->residual_scale = absl::GetFlag(FLAGS_residual_scale);
  config->termination_distance = absl::GetFlag(FLAGS_termination_distance);
  if (!absl::GetFlag(FLAGS_termination_bodies).empty()) config->termination_bodies = absl::GetFlag(FLAGS_termination_bodies);
  if (const std::string curriculum = absl::GetFlag(FLAGS_termination_curriculum); !curriculum.empty()) {
    const std::vector<std::string> ends = absl::StrSplit(curriculum, ':');
    if (ends.size() != 2 || !absl::SimpleAtod(ends[0], &config->curriculum_start) ||
        !absl::SimpleAtod(ends[1], &config->curriculum_end)) {
      return absl::InvalidArgumentError(
          absl::StrCat("--termination_curriculum: '", curriculum.substr(0, 64), "' is not START:END in m"));
    }
  }
  config->update_threads = absl::GetFlag(FLAGS_update_threads);
  config->collect_during_update = absl::GetFlag(FLAGS_collect_during_update);
  config->normalize_value = absl::GetFlag(FLAGS_normalize_value);
  config->seed = absl::GetFlag(FLAGS_seed);
  config->checkpoint_every = absl::GetFlag(FLAGS_checkpoint_every);
  config->report_every = absl::GetFlag(FLAGS_report_every);
  config->resume = absl::GetFlag(FLAGS_resume);
  config->server_timeout_s = absl::GetFlag(FLAGS_server_timeout_s);
  config->data_parallel.world_size = absl::GetFlag(FLAGS_world_size);
  config->data_parallel.rank = absl::GetFlag(FLAGS_rank);
  config->data_parallel.rendezvous = absl::GetFlag(FLAGS_rendezvous);
  config->data_parallel.rendezvous_timeout_s = absl::GetFlag(FLAGS_rendezvous_timeout_s);
  config->data_parallel.collective_timeout_s = absl::GetFlag(FLAGS_collective_timeout_s);
  if (absl::Status status = config->Validate(); !status.ok()) return status;
  return config;
}

// Whatever stopped the run, its last state goes to disk: the checkpoint and the exported policy.
int SaveFinalState(Trainer& trainer, const TrainerConfig& config) {
  if (absl::Status saved = trainer.SaveCheckpoint(config.run_dir + "/checkpoint.pt"); !saved.ok()) {
    return Fail(std::string(saved.message()));
  }
  if (absl::Status exported = trainer.ExportPolicy(config.run_dir + "/policy.pt"); !exported.ok()) {
    return Fail(std::string(exported.message()));
  }
  LogLine("done: %d iterations, %lld env steps; checkpoint %s/checkpoint.pt, policy %s/policy.pt",
          trainer.iteration(), static_cast<long long>(trainer.env_steps()), config.run_dir, config.run_dir);
  return 0;
}

int RunTraining(const std::string& token) {
  auto config = ConfigFromFlags(token);
  if (!config.ok()) return Fail(std::string(config.status().message()), 2);
  auto milestones = ParseMilestones(absl::GetFlag(FLAGS_milestones));
  if (!milestones.ok()) return Fail(std::string(milestones.status().message()), 2);
  const int keep_best_every = absl::GetFlag(FLAGS_keep_best_every);
  if (absl::Status settings = keep_best_every != 0 ? BestPolicyKeeper::CheckSettings(*config, keep_best_every)
                                                   : absl::OkStatus();
      !settings.ok()) {
    return Fail(std::string(settings.message()), 2);
  }
  auto trainer = Trainer::Create(*config);
  if (!trainer.ok()) return Fail(std::string(trainer.status().message()));
  std::unique_ptr<TensorBoardWriter> events;
  std::unique_ptr<CsvLogger> csv;
  if ((*trainer)->writes_run_dir()) {  // data-parallel ranks other than 0 write nothing
    auto opened_events = TensorBoardWriter::Open(config->run_dir);
    if (!opened_events.ok()) return Fail(std::string(opened_events.status().message()));
    auto opened_csv = CsvLogger::Open(config->run_dir + "/progress.csv", ProgressColumns(**trainer),
                                      config->resume ? CsvLogger::Start::kAppend : CsvLogger::Start::kFresh);
    if (!opened_csv.ok()) return Fail(std::string(opened_csv.status().message()));
    events = *std::move(opened_events);
    csv = *std::move(opened_csv);
  }

  std::unique_ptr<SimulationClient> eval_client;
  std::unique_ptr<BestPolicyKeeper> keeper;
  if (keep_best_every != 0 && (*trainer)->writes_run_dir()) {
    auto connected = ConnectToFirstServer(token);
    if (!connected.ok()) return Fail(absl::StrCat("--keep_best_every: ", connected.status().message()));
    eval_client = *std::move(connected);
    auto created = BestPolicyKeeper::Create(**trainer, eval_client.get(), keep_best_every);
    if (!created.ok()) return Fail(std::string(created.status().message()));
    keeper = *std::move(created);
  }

  IterationReporter reporter{trainer->get(), events.get(), csv.get(), *std::move(milestones), &g_stop};
  reporter.SkipPassedMilestones();
  reporter.start = absl::Now();
  reporter.budget_min = absl::GetFlag(FLAGS_time_budget_min);
  reporter.first = (*trainer)->iteration();
  reporter.last = reporter.first + config->iterations;
  const TrainerConfig& used = (*trainer)->config();  // a task run's sizes and action mode are its skills'
  LogLine("training %s preset on --servers %s, %d envs each, task %s, layout %s%s%s, %s actions, run dir %s",
          used.model.preset, absl::StrJoin(used.servers, ","), used.envs_per_server, used.task, used.part_layout,
          used.model.whole_body ? ", whole-body controller" : "", used.model.attention ? "" : ", no attention",
          used.action_mode, used.run_dir);
  absl::Status status = (*trainer)->Run(
      [&](const IterationStats& s) {
        reporter.Report(s);
        if (keeper == nullptr) return;
        // A failed evaluation (its server restarting, say) costs this draw, not the run.
        if (absl::Status kept = keeper->AfterIteration(**trainer); !kept.ok()) {
          LogLine("warning: --keep_best_every: %s", kept.message());
        }
      },
      &g_stop);
  if (!status.ok()) return Fail(std::string(status.message()));
  if (!(*trainer)->writes_run_dir()) return 0;
  return SaveFinalState(**trainer, *config);
}

}  // namespace
}  // namespace modskill::learner

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage(
      "trains or evaluates a ModSkill policy against modskill simulation servers.\n"
      "  modskill-learner --servers host:port --run_dir DIR --preset small --iterations N\n"
      "  modskill-learner --world_size 2 --rank 0|1 --rendezvous HOST0:29500 --servers ... --run_dir DIR\n"
      "  modskill-learner --eval --checkpoint DIR/policy.pt --servers host:port\n"
      "  modskill-learner --task steer --skills TRACKER/policy.pt --servers host:port --run_dir DIR\n"
      "  modskill-learner --eval --task steer --checkpoint DIR/policy.pt --servers host:port --task_baselines\n"
      "  modskill-learner --family deepmimic_jump --param gravity=4:14 --servers host:port --run_dir DIR");
  // --param may come several times, which absl alone would reduce to the last.
  const std::vector<std::string> family_params = modskill::learner::RepeatedFlagValues(argc, argv, "param");
  absl::ParseCommandLine(argc, argv);
  using namespace modskill::learner;
  signal(SIGINT, OnSignal);
  signal(SIGTERM, OnSignal);
  modskill::SetTorchThreads(std::max(1, absl::GetFlag(FLAGS_threads)));
  std::string token;
  if (!absl::GetFlag(FLAGS_auth_token_file).empty()) {
    auto read = modskill::ReadTokenFile(absl::GetFlag(FLAGS_auth_token_file));
    if (!read.ok()) return Fail(absl::StrCat("--auth_token_file: ", read.status().message()), 2);
    token = *read;
  }
  if (FamilyRequested()) return RunFamilyTraining(token, family_params, g_stop);
  if (!absl::GetFlag(FLAGS_eval)) return RunTraining(token);
  return absl::GetFlag(FLAGS_task) == "tracking" ? RunEvaluation(token) : RunTaskEvaluation(token);
}
