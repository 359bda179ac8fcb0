// Task sessions over gRPC: Describe lists the tasks, a session runs one (its spec, goal and
// reward terms equal the in-process env's), and bad task names or settings are refused naming
// the field.
#include <algorithm>
#include <cmath>
#include <map>

#include <gmock/gmock.h>

#include "common/wire/tensor_codec.h"
#include "tests/server_fixture.h"
#include "tests/simulation_server_fixture.h"

namespace modskill {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

TEST_F(SimulationServerTest, DescribeListsTheTasks) {
  auto spec = client_->Describe();
  ASSERT_TRUE(spec.ok()) << spec.status();
  EXPECT_EQ(spec->task(), "tracking");
  EXPECT_EQ(spec->goal_obs().size(), 0);
  std::vector<std::string> names;
  for (const v1::TaskInfo& task : spec->tasks()) {
    names.push_back(task.name());
    EXPECT_FALSE(task.description().empty()) << task.name();
    EXPECT_EQ(task.reward_terms(task.reward_terms_size() - 1), "energy") << task.name();
  }
  EXPECT_THAT(names, ElementsAre("tracking", "steer", "reach", "strike", "vr_tracking"));
  EXPECT_EQ(spec->tasks(1).goal_size(), 3);
  EXPECT_THAT(spec->tasks(1).reward_terms(), ElementsAre("speed", "facing", "energy"));
  EXPECT_EQ(spec->tasks(3).goal_size(), 15);
  EXPECT_EQ(spec->tasks(4).goal_size(), 72);
  // VR tracking watches the head and hands only; the others watch every body or none.
  EXPECT_THAT(spec->tasks(4).tracked_bodies(), ElementsAre("Head", "L_Hand", "R_Hand"));
  for (int t = 0; t < 4; ++t) EXPECT_EQ(spec->tasks(t).tracked_bodies_size(), 0) << spec->tasks(t).name();
}

TEST_F(SimulationServerTest, SteerSessionEqualsTheInProcessTaskEnv) {
  v1::SessionConfig config = Config(3, 21);
  config.set_task("steer");
  config.set_action_mode(v1::RESIDUAL);
  config.add_motions("deepmimic_walk");
  config.mutable_task_settings()->set_min_speed(1.0f);
  config.mutable_task_settings()->set_max_speed(1.5f);
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok()) << stream.status();
  const v1::EnvSpec& spec = (*stream)->opened().spec();
  EXPECT_EQ(spec.task(), "steer");
  EXPECT_EQ(spec.obs_size(), 934 + 3);
  EXPECT_EQ(spec.goal_obs().start(), 934);
  EXPECT_EQ(spec.goal_obs().size(), 3);
  EXPECT_THAT(spec.reward_terms(), ElementsAre("speed", "facing", "energy"));
  // The parts' slices are tracking's: each body's self features, then its base motion's.
  EXPECT_EQ(spec.parts(0).self_obs(0).start(), 0);
  EXPECT_EQ(spec.parts(0).obs().size(), spec.parts(0).self_obs_size() * (15 + 24));

  EnvBatchConfig local_config;
  local_config.num_envs = 3;
  local_config.seed = 21;
  local_config.env.task = TaskKind::kSteer;
  local_config.env.action.mode = ActionMode::kResidual;
  local_config.env.task_settings.min_speed = 1.0;
  local_config.env.task_settings.max_speed = 1.5;
  auto subset = DefaultMotions()->Subset({"deepmimic_walk"});
  ASSERT_TRUE(subset.ok());
  auto local = MakeBatch(local_config, std::make_shared<const MotionLibrary>(*std::move(subset)));
  ASSERT_NE(local, nullptr);
  local->Reset();
  std::vector<float> obs;
  ASSERT_TRUE(ReadFloatTensor((*stream)->opened().initial().obs(), "obs", &obs).ok());
  ASSERT_EQ(obs, local->buffers().obs);
  for (int i = 0; i < 3; ++i) {
    const float speed = obs[i * 937 + 936];
    EXPECT_GE(speed, 1.0f);
    EXPECT_LE(speed, 1.5f);
  }
  const std::vector<float> actions(3 * 69, 0.f);
  for (int s = 0; s < 8; ++s) {
    ASSERT_TRUE(local->Step(actions).ok());
    ASSERT_TRUE((*stream)->Step(actions.data()).ok());
    const v1::StepResult& result = (*stream)->result();
    std::vector<float> remote;
    ASSERT_TRUE(ReadFloatTensor(result.obs(), "obs", &remote).ok());
    ASSERT_EQ(remote, local->buffers().obs) << s;
    ASSERT_TRUE(ReadFloatTensor(result.reward_terms(), "reward_terms", &remote).ok());
    ASSERT_EQ(remote, local->buffers().reward_terms) << s;
    EXPECT_EQ(result.reward_terms().shape(1), 3);
  }
  EXPECT_TRUE((*stream)->Close().ok());
}

TEST_F(SimulationServerTest, BadTasksAreRejectedNamingTheField) {
  struct Case {
    v1::SessionConfig config;
    std::string message;
  };
  std::vector<Case> cases;
  v1::SessionConfig config = Config(2);
  config.set_task("strik");
  cases.push_back({config, "task: unknown task 'strik'"});
  config = Config(2);
  config.set_task("steer");
  config.mutable_task_settings()->set_min_speed(-2.f);
  cases.push_back({config, "task_settings.min_speed"});
  config.mutable_task_settings()->set_min_speed(2.f);
  config.mutable_task_settings()->set_max_speed(1.f);
  cases.push_back({config, "task_settings.max_speed"});
  config = Config(2);
  config.set_task("reach");
  config.mutable_task_settings()->set_max_goal_interval_s(std::nanf(""));
  cases.push_back({config, "task_settings.max_goal_interval_s"});
  config = Config(2);
  config.set_task("reach");
  config.mutable_task_settings()->set_reach_box_size(0.f);  // set, so not the default
  cases.push_back({config, "task_settings.reach_box_size"});
  config = Config(2);
  config.set_task("strike");
  config.mutable_task_settings()->set_steering_rate(1000.f);
  cases.push_back({config, "task_settings.steering_rate"});
  config = Config(2);
  config.set_task("reach");
  config.mutable_task_settings()->set_reach_center_z(0.f);  // half the default box underground
  cases.push_back({config, "task_settings.reach_center_z"});
  config = Config(2);
  config.set_task("steer");
  config.set_loop_clips(true);
  cases.push_back({config, "loop_clips: tracking only"});
  config = Config(2);
  config.set_task("vr_tracking");
  config.set_anchor_reference(true);
  cases.push_back({config, "anchor_reference: tracking only"});
  config = Config(2);
  config.set_anchor_position_only(true);
  cases.push_back({config, "anchor_position_only: set, but anchor_reference is not"});
  config = Config(2);
  config.set_anchor_reference(true);
  v1::FamilyParameterRange* gravity = config.mutable_family()->add_params();
  gravity->set_name("gravity");
  gravity->set_lo(5);
  gravity->set_hi(9);
  cases.push_back({config, "anchor_reference: not for a family session"});
  config = Config(2);
  config.set_reference_frames(9);
  cases.push_back({config, "reference_frames: 9 is not in [1, 8]"});
  config = Config(2);
  config.set_reference_frames(-1);
  cases.push_back({config, "reference_frames: -1 is not in [1, 8]"});
  config = Config(2);
  config.set_task("steer");
  config.set_reference_frames(2);
  cases.push_back({config, "reference_frames: 2 for task steer; tracking only"});
  config = Config(2);
  config.set_loop_clips(true);
  config.set_reference_frames(3);
  cases.push_back({config, "reference_frames: 3 with loop_clips"});
  config = Config(2);
  config.set_anchor_reference(true);
  config.set_reference_frames(3);
  cases.push_back({config, "reference_frames: 3 with anchor_reference"});
  for (const Case& c : cases) {
    auto stream = client_->OpenSession(c.config);
    ASSERT_FALSE(stream.ok()) << c.message;
    EXPECT_EQ(stream.status().code(), absl::StatusCode::kInvalidArgument) << stream.status();
    EXPECT_THAT(std::string(stream.status().message()), HasSubstr(c.message));
  }
  // The server still serves.
  config = Config(2);
  config.set_task("vr_tracking");
  auto vr = client_->OpenSession(config);
  ASSERT_TRUE(vr.ok()) << vr.status();
  EXPECT_EQ((*vr)->opened().spec().obs_size(), 358 + 72);
}

// Rollout runs a policy in the task it was trained for and reports the normalized return; a
// request for another task is refused naming it.
TEST_F(SimulationServerTest, RolloutRunsATaskPolicyInItsTask) {
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(OpenLoopPolicyBytes(TaskKind::kSteer));
  request.add_clips("deepmimic_walk");
  request.add_clips("deepmimic_run");
  request.set_max_steps_per_clip(40);
  request.set_seed(3);
  request.set_stream_frames(true);
  int frames = 0;
  auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame&) { ++frames; });
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  ASSERT_EQ(metrics->size(), 2u);
  int steps = 0;
  for (const v1::ClipMetrics& clip : *metrics) {
    // Walking open loop earns some of the steer reward but never all of it.
    EXPECT_GT(clip.normalized_return(), 0.0) << clip.clip();
    EXPECT_LT(clip.normalized_return(), 1.0) << clip.clip();
    EXPECT_LE(clip.steps(), 40);
    steps += clip.steps();
  }
  EXPECT_EQ(frames, steps + 2);
  // The same request again gives the same figures (the goals' seed).
  auto again = client_->Rollout(request);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ((*again)[0].normalized_return(), (*metrics)[0].normalized_return());

  request.set_task("reach");
  auto other = client_->Rollout(request);
  ASSERT_FALSE(other.ok());
  EXPECT_EQ(other.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(other.status().message()), HasSubstr("trained for steer"));
  // A tracker cannot run a task, nor a task policy tracking.
  request.set_checkpoint_bytes(OpenLoopPolicyBytes());
  request.set_task("steer");
  auto tracker = client_->Rollout(request);
  ASSERT_FALSE(tracker.ok());
  EXPECT_EQ(tracker.status().code(), absl::StatusCode::kFailedPrecondition);
  request.set_task("");
  request.mutable_task_settings()->set_max_speed(50.f);
  auto bad = client_->Rollout(request);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(std::string(bad.status().message()), HasSubstr("task_settings.max_speed"));
}

// A VR tracking rollout ends on its tracked bodies' mean error, and reports that mean: each
// frame's, the clip's largest (so success at stricter distances is the task's too), and success
// exactly when that largest stays within the 0.5 m of evaluation termination.
TEST_F(SimulationServerTest, VrRolloutMeasuresTheBodiesItTracks) {
  auto spec = client_->Describe();
  ASSERT_TRUE(spec.ok()) << spec.status();
  std::vector<int> tracked;
  for (const std::string& body : spec->tasks(4).tracked_bodies()) {
    tracked.push_back(std::find(spec->body_names().begin(), spec->body_names().end(), body) - spec->body_names().begin());
  }
  ASSERT_EQ(tracked.size(), 3u);
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(OpenLoopPolicyBytes(TaskKind::kVrTracking));
  for (const char* clip : {"deepmimic_walk", "deepmimic_backflip", "deepmimic_cartwheel"}) request.add_clips(clip);
  request.set_termination(v1::EVALUATION);
  request.set_termination_distance(0.5f);
  request.set_stream_frames(true);
  std::map<std::string, double> largest_tracked, largest_every_body;
  auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame& frame) {
    std::vector<float> sim, ref;
    ASSERT_TRUE(ReadFloatTensor(frame.sim_body_pos(), "sim_body_pos", &sim).ok());
    ASSERT_TRUE(ReadFloatTensor(frame.ref_body_pos(), "ref_body_pos", &ref).ok());
    const auto distance = [&](int b) {
      return std::hypot(sim[3 * b] - ref[3 * b], sim[3 * b + 1] - ref[3 * b + 1], sim[3 * b + 2] - ref[3 * b + 2]);
    };
    double mean_tracked = 0, mean_every_body = 0;
    for (int b : tracked) mean_tracked += distance(b) / tracked.size();
    const int bodies = static_cast<int>(sim.size() / 3);
    for (int b = 0; b < bodies; ++b) mean_every_body += distance(b) / bodies;
    EXPECT_NEAR(frame.mean_body_error_m(), mean_tracked, 1e-4);
    largest_tracked[frame.clip()] = std::max(largest_tracked[frame.clip()], mean_tracked);
    largest_every_body[frame.clip()] = std::max(largest_every_body[frame.clip()], mean_every_body);
  });
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  ASSERT_EQ(metrics->size(), 3u);
  bool differs = false;
  for (const v1::ClipMetrics& clip : *metrics) {
    EXPECT_NEAR(clip.max_mean_body_error_m(), largest_tracked[clip.clip()], 1e-4) << clip.clip();
    EXPECT_EQ(clip.success(), clip.max_mean_body_error_m() <= 0.5) << clip.clip();
    differs |= std::abs(largest_tracked[clip.clip()] - largest_every_body[clip.clip()]) > 0.01;
  }
  EXPECT_TRUE(differs) << "the three points' error should not be every body's";
}

}  // namespace
}  // namespace modskill
