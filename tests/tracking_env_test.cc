// The tracking env and the batch: reference state initialization, observation layout, reward,
// termination, determinism and bad input.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <gtest/gtest.h>

#include "server/core/env/base_motion_anchor.h"
#include "server/core/env/observation.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

EnvBatchConfig SmallConfig(int envs = 8, int threads = 1, uint64_t seed = 3) {
  EnvBatchConfig config;
  config.num_envs = envs;
  config.num_threads = threads;
  config.seed = seed;
  return config;
}

TEST(EnvSpecTest, FivePartLayoutHasContiguousPerPartSlices) {
  auto batch = MakeBatch(SmallConfig());
  ASSERT_NE(batch, nullptr);
  const EnvSpec& spec = batch->spec();
  EXPECT_EQ(spec.obs_size, 934);
  EXPECT_EQ(spec.self_obs_size, 358);
  EXPECT_EQ(spec.task_obs_size, 576);
  EXPECT_EQ(spec.action_size, 69);
  EXPECT_EQ(spec.amp_obs_per_frame, 232);
  EXPECT_EQ(spec.amp_obs_size, 2320);
  ASSERT_EQ(spec.part_action.size(), 5u);
  const int expected_actions[] = {12, 12, 15, 15, 15};
  int obs_end = 0, action_end = 0;
  for (int p = 0; p < 5; ++p) {
    EXPECT_EQ(spec.part_action[p].size, expected_actions[p]) << p;
    EXPECT_EQ(spec.part_obs[p].start, obs_end);
    EXPECT_EQ(spec.part_action[p].start, action_end);
    obs_end += spec.part_obs[p].size;
    action_end += spec.part_action[p].size;
  }
  EXPECT_EQ(obs_end, spec.obs_size);
  EXPECT_EQ(action_end, spec.action_size);
  // Every hinge is driven by exactly one action, and each action belongs to its part's bodies.
  std::vector<int> seen(69, 0);
  for (int hinge : spec.action_hinge) ++seen[hinge];
  for (int h = 0; h < 69; ++h) EXPECT_EQ(seen[h], 1) << h;
  EXPECT_EQ(spec.joint_names[0], "L_Hip_x");
  EXPECT_EQ(spec.joint_names[spec.part_action[2].start], "Torso_x");
}

TEST(EnvSpecTest, EveryShippedLayoutCoversTheBodyOnce) {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  ASSERT_TRUE(catalog.ok()) << catalog.status();
  for (const char* name : {"5part", "3part", "2part", "1part"}) {
    auto layout = catalog->Get(name);
    ASSERT_TRUE(layout.ok()) << name;
    std::vector<int> order = layout->BodyOrder();
    std::sort(order.begin(), order.end());
    for (int b = 0; b < 24; ++b) EXPECT_EQ(order[b], b) << name;
    EnvBatchConfig config = SmallConfig(2);
    config.part_layout = name;
    auto batch = MakeBatch(config);
    ASSERT_NE(batch, nullptr);
    EXPECT_EQ(batch->spec().obs_size, 934);
    EXPECT_EQ(batch->spec().layout.num_parts(), std::atoi(name));
  }
  auto unknown = catalog->Get("7part");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("7part"), std::string::npos);
  auto duplicate = MakePartLayout("dup", {{"a", {"Pelvis", "Pelvis"}}}, DefaultSpec());
  ASSERT_FALSE(duplicate.ok());
  EXPECT_NE(duplicate.status().message().find("two parts"), std::string::npos);
  auto missing = MakePartLayout("partial", {{"a", {"Pelvis"}}}, DefaultSpec());
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.status().message().find("L_Hip"), std::string::npos);
  auto bad_body = MakePartLayout("typo", {{"a", {"Pelvsi"}}}, DefaultSpec());
  ASSERT_FALSE(bad_body.ok());
  EXPECT_NE(bad_body.status().message().find("Pelvsi"), std::string::npos);
}

TEST(TrackingEnvTest, ResetOntoReferenceHasZeroDeltasAndMaximalReward) {
  auto batch = MakeBatch(SmallConfig(1));
  ASSERT_NE(batch, nullptr);
  const MotionLibrary& motions = batch->motions();
  for (const char* name : {"deepmimic_walk", "cmu_02_01", "deepmimic_backflip"}) {
    const int clip = motions.Find(name);
    ASSERT_GE(clip, 0);
    batch->env(0).ResetTo(clip, 10, batch->row(0));
    float terms[kNumRewardTerms] = {};
    const TrackingErrors errors = batch->env(0).CurrentTrackingTerms(terms);
    EXPECT_LT(errors.max_body_distance, 1e-9) << name;
    EXPECT_NEAR(terms[kRewardPos] + terms[kRewardRot] + terms[kRewardVel] + terms[kRewardAngVel], 1.0, 1e-6) << name;
    // The task part of the observation against the same frame is all zero deltas.
    HumanoidState sim, ref;
    sim.Resize(24, 69);
    ref.Resize(24, 69);
    ReadSimulatedState(batch->humanoid(), batch->env(0).data(), &sim);
    ReadReferenceState(motions.clip(clip), 10, &ref);
    std::vector<float> obs(batch->spec().obs_size);
    WriteTrackingObservation(batch->spec(), sim, ref, obs.data());
    for (int body = 0; body < 24; ++body) {
      const int self = body == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody;
      const float* task = &obs[batch->spec().body_obs_start[body] + self];
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(task[k], 0.f, 1e-6) << name << " dpos body " << body;
      // Identity rotation in tangent-normal form: (1, 0, 0, 0, 0, 1).
      const float identity[6] = {1, 0, 0, 0, 0, 1};
      for (int k = 0; k < 6; ++k) EXPECT_NEAR(task[3 + k], identity[k], 1e-6) << name << " drot body " << body;
      for (int k = 9; k < 15; ++k) EXPECT_NEAR(task[k], 0.f, 1e-5) << name << " dvel body " << body;
    }
    EXPECT_EQ(batch->buffers().clip_id[0], clip);
    EXPECT_EQ(batch->buffers().frame[0], 10);
  }
}

// SessionConfig.reference_frames: each body's observation holds one task block per upcoming
// frame, the next one first, and a frame past the clip's end repeats its last; block 0 and the
// self features are what a one-frame tracker observes.
TEST(TrackingEnvTest, ObservesUpcomingReferenceFramesClampedAtTheClipsEnd) {
  EnvBatchConfig config = SmallConfig(1);
  config.env.reference_frames = 3;
  auto batch = MakeBatch(config);
  ASSERT_NE(batch, nullptr);
  auto one_frame = MakeBatch(SmallConfig(1));
  ASSERT_NE(one_frame, nullptr);
  const EnvSpec& spec = batch->spec();
  EXPECT_EQ(spec.reference_frames, 3);
  EXPECT_EQ(spec.obs_size, 358 + 3 * 576);
  EXPECT_EQ(spec.task_obs_size, 3 * 576);
  const int clip = batch->motions().Find("deepmimic_walk");
  ASSERT_GE(clip, 0);
  const MotionClip& walk = batch->motions().clip(clip);
  const int last = walk.num_frames - 1;
  HumanoidState sim, upcoming;
  sim.Resize(24, 69);
  upcoming.Resize(24, 69);
  for (int frame : {5, last - 2}) {
    batch->env(0).ResetTo(clip, frame, batch->row(0));
    one_frame->env(0).ResetTo(clip, frame, one_frame->row(0));
    ReadSimulatedState(batch->humanoid(), batch->env(0).data(), &sim);
    const float* obs = batch->buffers().obs.data();
    const float* single = one_frame->buffers().obs.data();
    for (int body = 0; body < 24; ++body) {
      const int self = body == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody;
      const float* mine = obs + spec.body_obs_start[body];
      const float* theirs = single + one_frame->spec().body_obs_start[body];
      for (int f = 0; f < self + kTaskFeaturesPerBody; ++f) {
        ASSERT_EQ(mine[f], theirs[f]) << "frame " << frame << " body " << body << " feature " << f;
      }
      for (int k = 1; k < 3; ++k) {
        ReadReferenceState(walk, std::min(frame + 1 + k, last), &upcoming);
        float expected[kTaskFeaturesPerBody];
        WriteBodyTaskFeatures(sim, upcoming, body, expected);
        for (int f = 0; f < kTaskFeaturesPerBody; ++f) {
          ASSERT_NEAR(mine[self + k * kTaskFeaturesPerBody + f], expected[f], 1e-6)
              << "frame " << frame << " block " << k << " body " << body << " feature " << f;
        }
      }
    }
  }
  // Near the end the last two blocks both show the clip's last frame.
  const int root_block = spec.body_obs_start[0] + kSelfFeaturesRoot;
  const float* obs = batch->buffers().obs.data();
  for (int f = 0; f < kTaskFeaturesPerBody; ++f) {
    EXPECT_EQ(obs[root_block + kTaskFeaturesPerBody + f], obs[root_block + 2 * kTaskFeaturesPerBody + f]) << f;
  }
  // A step keeps the layout: the next observation's block 1 is the frame two steps ahead.
  batch->env(0).ResetTo(clip, 5, batch->row(0));
  ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
  ReadSimulatedState(batch->humanoid(), batch->env(0).data(), &sim);
  ReadReferenceState(walk, 8, &upcoming);
  float expected[kTaskFeaturesPerBody];
  WriteBodyTaskFeatures(sim, upcoming, 0, expected);
  for (int f = 0; f < kTaskFeaturesPerBody; ++f) {
    EXPECT_NEAR(batch->buffers().obs[root_block + kTaskFeaturesPerBody + f], expected[f], 1e-6) << f;
  }
}

TEST(TrackingEnvTest, TrackingReferenceActionsKeepsTheEpisodeAlive) {
  auto batch = MakeBatch(SmallConfig(1));
  ASSERT_NE(batch, nullptr);
  const int clip = batch->motions().Find("deepmimic_walk");
  batch->env(0).ResetTo(clip, 0, batch->row(0));
  for (int s = 0; s < 5; ++s) {
    ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
    EXPECT_EQ(batch->buffers().done[0], 0) << s;
    EXPECT_GT(batch->buffers().reward[0], 0.3f) << s;
    EXPECT_LT(batch->buffers().max_body_error[0], 0.25f) << s;
  }
  EXPECT_EQ(batch->buffers().frame[0], 5);
}

TEST(TrackingEnvTest, PushingABodyAwayTerminatesInTrainingMode) {
  auto batch = MakeBatch(SmallConfig(1));
  ASSERT_NE(batch, nullptr);
  const int clip = batch->motions().Find("deepmimic_walk");
  batch->env(0).ResetTo(clip, 5, batch->row(0));
  // Training termination never happens on the first step after a reset (PHC).
  ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
  ASSERT_EQ(batch->buffers().done[0], 0);
  // Swing the left shoulder far from the reference: the hand ends up > 0.25 m away.
  const int shoulder = DefaultSpec().BodyIndex("L_Shoulder");
  batch->env(0).mutable_data()->qpos[7 + 3 * (shoulder - 1) + 2] += 1.5;
  batch->env(0).RefreshObservation(batch->row(0));
  ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
  EXPECT_EQ(batch->buffers().done[0], 1);
  EXPECT_EQ(batch->buffers().truncated[0], 0);
  EXPECT_GT(batch->buffers().max_body_error[0], 0.25f);
  EXPECT_EQ(batch->buffers().ended_clip_id[0], clip);
  EXPECT_EQ(batch->buffers().ended_frame[0], 7);

  // The same push in evaluation mode (mean body error > 0.5 m) does not end the episode...
  EnvBatchConfig eval = SmallConfig(1);
  eval.env.termination = TerminationMode::kEvaluation;
  eval.env.termination_distance = 0.5;
  auto evaluation = MakeBatch(eval);
  evaluation->env(0).ResetTo(clip, 5, evaluation->row(0));
  evaluation->env(0).mutable_data()->qpos[7 + 3 * (shoulder - 1) + 2] += 1.5;
  evaluation->env(0).RefreshObservation(evaluation->row(0));
  ASSERT_TRUE(evaluation->Step(ReferenceActions(*evaluation)).ok());
  EXPECT_EQ(evaluation->buffers().done[0], 0);
  // ...but moving the whole body a meter away does.
  evaluation->env(0).mutable_data()->qpos[0] += 1.0;
  evaluation->env(0).RefreshObservation(evaluation->row(0));
  ASSERT_TRUE(evaluation->Step(ReferenceActions(*evaluation)).ok());
  EXPECT_EQ(evaluation->buffers().done[0], 1);
  EXPECT_EQ(evaluation->buffers().truncated[0], 0);
}

TEST(TrackingEnvTest, ClipEndTruncatesAndResets) {
  EnvBatchConfig config = SmallConfig(1);
  config.env.termination = TerminationMode::kNone;
  auto batch = MakeBatch(config);
  const int clip = batch->motions().Find("deepmimic_walk");
  const int frames = batch->motions().clip(clip).num_frames;
  batch->env(0).ResetTo(clip, frames - 4, batch->row(0));
  for (int s = 0; s < 2; ++s) {
    ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
    EXPECT_EQ(batch->buffers().done[0], 0);
  }
  ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
  EXPECT_EQ(batch->buffers().done[0], 1);
  EXPECT_EQ(batch->buffers().truncated[0], 1);
  EXPECT_EQ(batch->buffers().ended_frame[0], frames - 1);
}

// SessionConfig.loop_clips: the clip's end does not end the episode; the reference goes on at
// frame 1 from where the last frame left it (not back at the clip's start), until the step limit.
TEST(TrackingEnvTest, LoopingClipGoesOnFromItsLastFrameUntilTheStepLimit) {
  EnvBatchConfig config = SmallConfig(1);
  config.env.termination = TerminationMode::kNone;
  config.env.loop_clips = true;
  config.env.max_episode_steps = 8;
  auto batch = MakeBatch(config);
  const int clip = batch->motions().Find("deepmimic_walk");
  const MotionClip& walk = batch->motions().clip(clip);
  const int frames = walk.num_frames;
  ASSERT_GT((walk.root_pos[frames - 1] - walk.root_pos[0]).head<2>().norm(), 0.5) << "a clip that travels";
  batch->env(0).ResetTo(clip, frames - 4, batch->row(0));
  const int root_dpos = batch->spec().body_obs_start[0] + kSelfFeaturesRoot;
  std::vector<int> frames_reached;
  for (int s = 0; s < 7; ++s) {
    ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
    ASSERT_EQ(batch->buffers().done[0], 0) << s;
    frames_reached.push_back(batch->buffers().frame[0]);
    const float* dpos = &batch->buffers().obs[root_dpos];
    EXPECT_LT(std::hypot(dpos[0], dpos[1]), 0.3) << "step " << s << ": the next reference root is near the character";
  }
  EXPECT_EQ(frames_reached, (std::vector<int>{frames - 3, frames - 2, frames - 1, 1, 2, 3, 4}));
  ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
  EXPECT_EQ(batch->buffers().done[0], 1);
  EXPECT_EQ(batch->buffers().truncated[0], 1) << "ended by the step limit";
}

// SessionConfig.anchor_reference: each step the reference is carried onto the character, as a
// goal task's base motion is. The open-loop reference's character drifts off the walk and falls;
// anchored, the next reference root stays one frame's travel away and the errors leave out the
// drift, where the unanchored reference walks on without it.
TEST(TrackingEnvTest, AnchoredReferenceGoesOnFromWhereTheCharacterIs) {
  struct Run {
    float farthest_root_gap = 0;  // next reference root to the character, horizontal (m)
    float last_mean_error = 0;
  };
  auto run = [](bool anchored) {
    EnvBatchConfig config = SmallConfig(1);
    config.env.termination = TerminationMode::kNone;
    config.env.loop_clips = true;
    config.env.anchor_reference = anchored;
    auto batch = MakeBatch(config);
    batch->env(0).ResetTo(batch->motions().Find("deepmimic_walk"), 0, batch->row(0));
    const int root_dpos = batch->spec().body_obs_start[0] + kSelfFeaturesRoot;
    Run result;
    for (int s = 0; s < 60; ++s) {
      EXPECT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
      EXPECT_EQ(batch->buffers().done[0], 0) << s;
      const float* dpos = &batch->buffers().obs[root_dpos];
      result.farthest_root_gap = std::max(result.farthest_root_gap, std::hypot(dpos[0], dpos[1]));
    }
    result.last_mean_error = batch->buffers().mean_body_error[0];
    return result;
  };
  const Run anchored = run(true), global = run(false);
  EXPECT_LT(anchored.farthest_root_gap, 0.1) << "one frame of a walk is ~4 cm";
  EXPECT_GT(global.farthest_root_gap, 0.5) << "the unanchored walk leaves the fallen character behind";
  // The errors measure against the carried reference: the drift is not in them (the open-loop
  // character has fallen by step 60: 1.0 m anchored, 1.3 m unanchored).
  EXPECT_LT(anchored.last_mean_error, global.last_mean_error - 0.1);
}

// SessionConfig.anchor_position_only: the reference stands on the character's root but keeps the
// clip's own heading (a loop's cycles turning it on), so a heading error stays in the observation.
TEST(TrackingEnvTest, ReferenceAnchoredInPositionOnlyKeepsTheClipsHeading) {
  EnvBatchConfig config = SmallConfig(1);
  config.env.termination = TerminationMode::kNone;
  config.env.loop_clips = true;
  config.env.anchor_reference = true;
  config.env.anchor_position_only = true;
  auto batch = MakeBatch(config);
  const int walk = batch->motions().Find("deepmimic_walk");
  const MotionClip& clip = batch->motions().clip(walk);
  const int last = clip.num_frames - 1;
  const double cycle_yaw = HeadingAngle(ClipCycleMotion(clip).yaw);
  batch->env(0).ResetTo(walk, 0, batch->row(0));
  const int root_task = batch->spec().body_obs_start[0] + kSelfFeaturesRoot;
  int cycles = 0;
  double largest_error = 0;
  for (int s = 0; s < 2 * last; ++s) {
    const int frame_before = batch->env(0).frame();
    ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
    ASSERT_EQ(batch->buffers().done[0], 0) << s;
    const int frame = batch->env(0).frame();
    if (frame < frame_before) ++cycles;
    const int next = frame >= last ? 1 : frame + 1;
    const double clip_heading = HeadingAngle(clip.local(next, 0)) + (cycles + (next < frame ? 1 : 0)) * cycle_yaw;
    const double* q = batch->env(0).data()->qpos;
    const double character = HeadingAngle(Quat(q[3], q[4], q[5], q[6]));
    const float* task = &batch->buffers().obs[root_task];
    const float* dpos = task;           // the reference root's offset, heading frame
    const float* reference_x = task + 18;  // its x axis, heading frame (tangent-normal, first half)
    EXPECT_LT(std::hypot(dpos[0], dpos[1]), 0.1) << "step " << s << ": the reference stands on the character";
    const double observed = character + std::atan2(reference_x[1], reference_x[0]);
    EXPECT_NEAR(WrapAngle(observed - clip_heading), 0.0, 1e-4) << "step " << s;
    largest_error = std::max(largest_error, std::abs(WrapAngle(character - clip_heading)));
  }
  EXPECT_EQ(cycles, 1) << "the loop wrapped";
  EXPECT_GT(largest_error, 0.05) << "the open-loop character turned off the clip's heading, and it shows";
}

TEST(BaseMotionAnchorTest, PlanarMotionsComposeAndACycleMovesTheFirstFrameOntoTheLast) {
  const MotionClip& walk = DefaultMotions()->clip(DefaultMotions()->Find("deepmimic_walk"));
  const PlanarMotion cycle = ClipCycleMotion(walk);
  const int last = walk.num_frames - 1;
  const Vec3 first = walk.root_pos[0];
  const Vec3 moved = cycle.yaw * first + cycle.shift;
  EXPECT_NEAR(moved.x(), walk.root_pos[last].x(), 1e-9);
  EXPECT_NEAR(moved.y(), walk.root_pos[last].y(), 1e-9);
  const PlanarMotion twice = cycle.After(cycle);
  const Vec3 p(0.3, -1.2, 0.9);
  EXPECT_LT(((twice.yaw * p + twice.shift) - (cycle.yaw * (cycle.yaw * p + cycle.shift) + cycle.shift)).norm(), 1e-12);
}

TEST(TrackingEnvTest, EnergyPenaltyIsOffRightAfterResetThenNegative) {
  auto batch = MakeBatch(SmallConfig(1));
  const int clip = batch->motions().Find("deepmimic_walk");
  batch->env(0).ResetTo(clip, 0, batch->row(0));
  std::vector<float> energy;
  for (int s = 0; s < 5; ++s) {
    ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
    energy.push_back(batch->buffers().reward_terms[kRewardEnergy]);
    ASSERT_EQ(batch->buffers().done[0], 0) << s;
  }
  EXPECT_EQ(energy[0], 0.f);
  EXPECT_EQ(energy[2], 0.f);
  EXPECT_LT(energy[3], 0.f);
  EXPECT_LT(energy[4], 0.f);
}

TEST(TrackingEnvTest, AmpHistoryShiftsByOneFramePerStep) {
  auto batch = MakeBatch(SmallConfig(1));
  const int clip = batch->motions().Find("deepmimic_walk");
  batch->env(0).ResetTo(clip, 12, batch->row(0));
  const int per_frame = batch->spec().amp_obs_per_frame;
  const std::vector<float> before = batch->buffers().amp_obs;
  // At reset the history is the reference's own past: frames 12, 11, 10, ...
  EXPECT_NE(std::memcmp(&before[0], &before[per_frame], sizeof(float) * per_frame), 0);
  ASSERT_TRUE(batch->Step(ReferenceActions(*batch)).ok());
  ASSERT_EQ(batch->buffers().done[0], 0);
  const std::vector<float>& after = batch->buffers().amp_obs;
  for (int k = 0; k + 1 < kAmpHistory; ++k) {
    EXPECT_EQ(std::memcmp(&after[(k + 1) * per_frame], &before[k * per_frame], sizeof(float) * per_frame), 0) << k;
  }
  // The newest frame is the simulated state: root height first, near the reference's.
  EXPECT_NEAR(after[0], batch->motions().clip(clip).body_pos[13 * 24].z(), 0.05);
}

TEST(EnvBatchTest, SameSeedGivesIdenticalBatchesForAnyThreadCount) {
  auto run = [](int threads) {
    auto batch = MakeBatch(SmallConfig(16, threads, 42));
    batch->Reset();
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> uniform(-1.f, 1.f);
    std::vector<float> trace;
    for (int s = 0; s < 40; ++s) {
      std::vector<float> actions = ReferenceActions(*batch);
      for (float& a : actions) a = std::clamp(a + 0.3f * uniform(rng), -1.f, 1.f);
      EXPECT_TRUE(batch->Step(actions).ok());
      const BatchBuffers& out = batch->buffers();
      trace.insert(trace.end(), out.obs.begin(), out.obs.end());
      trace.insert(trace.end(), out.reward.begin(), out.reward.end());
      trace.insert(trace.end(), out.amp_obs.begin(), out.amp_obs.end());
      for (int i = 0; i < batch->num_envs(); ++i) {
        trace.push_back(static_cast<float>(out.done[i]));
        trace.push_back(static_cast<float>(out.clip_id[i]));
        trace.push_back(static_cast<float>(out.frame[i]));
      }
    }
    return trace;
  };
  const std::vector<float> first = run(1);
  const std::vector<float> second = run(1);
  const std::vector<float> threaded = run(2);
  ASSERT_EQ(first.size(), second.size());
  EXPECT_EQ(std::memcmp(first.data(), second.data(), first.size() * sizeof(float)), 0);
  ASSERT_EQ(first.size(), threaded.size());
  EXPECT_EQ(std::memcmp(first.data(), threaded.data(), first.size() * sizeof(float)), 0);
  // A different seed samples different clips and frames.
  auto other = MakeBatch(SmallConfig(16, 1, 43));
  other->Reset();
  auto base = MakeBatch(SmallConfig(16, 1, 42));
  base->Reset();
  EXPECT_NE(other->buffers().frame, base->buffers().frame);
}

TEST(EnvBatchTest, BadActionsAreRejectedBeforeAnyEnvMoves) {
  auto batch = MakeBatch(SmallConfig(4));
  batch->Reset();
  const std::vector<float> obs_before = batch->buffers().obs;
  std::vector<float> actions(4 * 69, 0.f);
  auto short_batch = batch->Step(absl::MakeConstSpan(actions.data(), actions.size() - 1));
  ASSERT_FALSE(short_batch.ok());
  EXPECT_EQ(short_batch.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(short_batch.message().find("actions"), std::string::npos);
  EXPECT_NE(short_batch.message().find("276"), std::string::npos);
  actions[2 * 69 + 5] = std::numeric_limits<float>::quiet_NaN();
  auto nan = batch->Step(actions);
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.message().find("row 2"), std::string::npos);
  actions[2 * 69 + 5] = 0.f;
  actions[3 * 69] = std::numeric_limits<float>::infinity();
  auto inf = batch->Step(actions);
  ASSERT_FALSE(inf.ok());
  EXPECT_NE(inf.message().find("row 3"), std::string::npos);
  EXPECT_EQ(batch->buffers().obs, obs_before);
  EXPECT_EQ(batch->steps(), 0);
}

TEST(EnvBatchTest, PhysicsBlowUpResetsOnlyThatEnvAndIsCounted) {
  auto clean = MakeBatch(SmallConfig(4, 1, 11));
  auto broken = MakeBatch(SmallConfig(4, 1, 11));
  clean->Reset();
  broken->Reset();
  broken->env(1).mutable_data()->qvel[10] = std::numeric_limits<double>::quiet_NaN();
  const std::vector<float> actions = ReferenceActions(*clean);
  ASSERT_TRUE(clean->Step(actions).ok());
  ASSERT_TRUE(broken->Step(actions).ok());
  EXPECT_EQ(broken->physics_resets(), 1);
  EXPECT_EQ(clean->physics_resets(), 0);
  EXPECT_EQ(broken->buffers().done[1], 1);
  EXPECT_EQ(broken->buffers().reward[1], 0.f);
  for (float v : std::vector<float>(broken->buffers().obs.begin() + 934, broken->buffers().obs.begin() + 2 * 934)) {
    ASSERT_TRUE(std::isfinite(v));
  }
  const int obs = clean->spec().obs_size;
  for (int i : {0, 2, 3}) {
    EXPECT_EQ(std::memcmp(&clean->buffers().obs[i * obs], &broken->buffers().obs[i * obs], obs * sizeof(float)), 0) << i;
    EXPECT_EQ(clean->buffers().reward[i], broken->buffers().reward[i]) << i;
  }
}

TEST(EnvBatchTest, BadConfigsAreErrors) {
  EnvBatchConfig config = SmallConfig(0);
  auto zero = EnvBatch::Create(config, DefaultMotions());
  ASSERT_FALSE(zero.ok());
  EXPECT_NE(zero.status().message().find("num_envs"), std::string::npos);
  config = SmallConfig(2, 0);
  EXPECT_FALSE(EnvBatch::Create(config, DefaultMotions()).ok());
  config = SmallConfig(2);
  config.part_layout = "9part";
  auto layout = EnvBatch::Create(config, DefaultMotions());
  ASSERT_FALSE(layout.ok());
  EXPECT_NE(layout.status().message().find("9part"), std::string::npos);
  config = SmallConfig(2);
  config.physics.substeps = 0;
  auto substeps = EnvBatch::Create(config, DefaultMotions());
  ASSERT_FALSE(substeps.ok());
  EXPECT_NE(substeps.status().message().find("substeps"), std::string::npos);
  EXPECT_FALSE(EnvBatch::Create(SmallConfig(2), std::make_shared<const MotionLibrary>()).ok());
  for (int frames : {0, 9}) {
    config = SmallConfig(2);
    config.env.reference_frames = frames;
    auto bad = EnvBatch::Create(config, DefaultMotions());
    ASSERT_FALSE(bad.ok()) << frames;
    EXPECT_NE(bad.status().message().find("reference_frames"), std::string::npos);
  }
  config = SmallConfig(2);
  config.env.reference_frames = 2;
  config.env.loop_clips = true;
  EXPECT_FALSE(EnvBatch::Create(config, DefaultMotions()).ok());
}

TEST(ClipSamplerTest, FollowsWeightsAndRejectsBadOnes) {
  ClipSampler sampler(3);
  ASSERT_TRUE(sampler.SetWeights(std::vector<double>{0.0, 3.0, 1.0}).ok());
  std::mt19937_64 rng(1);
  int counts[3] = {};
  for (int k = 0; k < 4000; ++k) ++counts[sampler.Sample(rng)];
  EXPECT_EQ(counts[0], 0);
  EXPECT_NEAR(counts[1] / 4000.0, 0.75, 0.03);
  EXPECT_FALSE(sampler.SetWeights(std::vector<double>{1.0, 1.0}).ok());
  EXPECT_FALSE(sampler.SetWeights(std::vector<double>{1.0, -1.0, 1.0}).ok());
  EXPECT_FALSE(sampler.SetWeights(std::vector<double>{0.0, 0.0, 0.0}).ok());
  auto nan = sampler.SetWeights(std::vector<double>{1.0, std::nan(""), 1.0});
  ASSERT_FALSE(nan.ok());
  EXPECT_NE(nan.message().find("weights[1]"), std::string::npos);
}

}  // namespace
}  // namespace modskill
