// A motor-skill family's envs (server/core/env/family_episode.h): the spec, the time warp, the
// parameters reaching the physics (gravity, masses, the obstacle), the jump's spike, the fitness
// and bad parameter rows.
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "server/core/sim/mjcf_builder.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

std::shared_ptr<const MotionLibrary> Clip(const char* name) {
  auto subset = DefaultMotions()->Subset({name});
  EXPECT_TRUE(subset.ok()) << subset.status();
  return std::make_shared<const MotionLibrary>(*std::move(subset));
}

EnvBatchConfig FamilyConfig(std::vector<ParamRange> ranges, int envs = 2) {
  EnvBatchConfig config;
  config.num_envs = envs;
  config.seed = 5;
  config.env.action.mode = ActionMode::kResidual;
  config.env.termination_distance = kFamilyDefaultTerminationDistance;
  config.env.family = std::move(ranges);
  return config;
}

// Every env on `a` (one value per range) from its next episode on, then a reset.
void StartAll(EnvBatch& batch, const std::vector<float>& a) {
  std::vector<float> rows;
  for (int i = 0; i < batch.num_envs(); ++i) rows.insert(rows.end(), a.begin(), a.end());
  ASSERT_TRUE(batch.SetFamilyParameters(rows).ok());
  batch.Reset();
}

// Zero displacement and a time warp of tau for every env.
std::vector<float> Actions(const EnvBatch& batch, float tau) {
  std::vector<float> actions(static_cast<size_t>(batch.num_envs()) * batch.spec().action_size, 0.f);
  for (int i = 0; i < batch.num_envs(); ++i) actions[static_cast<size_t>(i) * batch.spec().action_size + batch.spec().time_warp_action] = tau;
  return actions;
}

// Env 0 leaves the floor at kTakeOff m/s: the open-loop clip alone does not get off the floor.
constexpr double kTakeOff = 2.5;
void Launch(EnvBatch& batch) { batch.env(0).mutable_data()->qvel[2] = kTakeOff; }

// The highest the root gets after a launch, until the episode ends (or 200 steps).
double RootApex(EnvBatch& batch) {
  double apex = 0;
  Launch(batch);
  const std::vector<float> actions = Actions(batch, 0.f);
  for (int step = 0; step < 200; ++step) {
    EXPECT_TRUE(batch.Step(actions).ok());
    if (batch.buffers().done[0]) break;
    apex = std::max(apex, batch.env(0).data()->qpos[2]);
  }
  return apex;
}

TEST(FamilyEnvTest, SpecAppendsParametersPhaseAndTimeWarp) {
  auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 4, 14}, {"jump_height", 1.0, 1.0}}), Clip("deepmimic_jump"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  const EnvSpec& spec = (*batch)->spec();
  EXPECT_EQ(spec.obs_size, 934 + 3);
  EXPECT_EQ(spec.goal_obs.start, 934);
  EXPECT_EQ(spec.goal_obs.size, 3);
  EXPECT_EQ(spec.action_size, 70);
  EXPECT_EQ(spec.time_warp_action, 69);
  EXPECT_EQ(spec.reward_terms.back(), "energy");
  EXPECT_NE(std::find(spec.reward_terms.begin(), spec.reward_terms.end(), "task"), spec.reward_terms.end());
  EXPECT_EQ((*batch)->buffers().widths.family_params, 2);
  // A tracking batch has none of it.
  EnvBatchConfig tracking;
  tracking.num_envs = 1;
  auto plain = EnvBatch::Create(tracking, Clip("deepmimic_jump"));
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ((*plain)->spec().time_warp_action, -1);
  EXPECT_TRUE((*plain)->spec().family.empty());
}

TEST(FamilyEnvTest, TimeWarpAdvancesThePhaseByExpOfClippedTau) {
  EXPECT_DOUBLE_EQ(PhaseStep(0.f), 1.0);
  EXPECT_DOUBLE_EQ(PhaseStep(0.4f), std::exp(1.5 * static_cast<double>(0.4f)));
  EXPECT_DOUBLE_EQ(PhaseStep(1.f), std::exp(1.0));    // clipped at 1
  EXPECT_DOUBLE_EQ(PhaseStep(-1.f), std::exp(-1.5));
  EXPECT_DOUBLE_EQ(PhaseStep(-5.f), std::exp(-2.0));  // clipped at -2
  auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 9.81, 9.81}}, 1), Clip("deepmimic_jump"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  EnvBatch& envs = **batch;
  envs.Reset();
  const int last = envs.motions().clip(0).num_frames - 1;
  double phase = 0;
  for (float tau : {0.f, -1.f, -1.f, 1.f, 0.f}) {
    ASSERT_TRUE(envs.Step(Actions(envs, tau)).ok());
    ASSERT_FALSE(envs.buffers().done[0]);
    phase += PhaseStep(tau);
    EXPECT_NEAR(envs.buffers().phase_step[0], PhaseStep(tau), 1e-6);
    EXPECT_NEAR(envs.env(0).family()->phase(), phase, 1e-9);
    EXPECT_EQ(envs.buffers().frame[0], static_cast<int>(std::floor(phase)));
    // The goal ends with the phase as a share of the clip.
    EXPECT_NEAR(envs.buffers().obs[envs.spec().goal_obs.start + 1], phase / last, 1e-6);
  }
}

TEST(FamilyEnvTest, ParametersReachTheEnvsOwnModel) {
  auto batch = EnvBatch::Create(
      FamilyConfig({{"gravity", 4, 14}, {"body_mass_scale", 0.5, 2}, {"obstacle_height", 0, 0.5}, {"obstacle_distance", 1, 3}}),
      Clip("deepmimic_walk"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  EnvBatch& envs = **batch;
  StartAll(envs, {5.f, 1.25f, 0.3f, 2.f});
  const mjModel* own = envs.env(0).family()->model();
  const mjModel* shared = envs.humanoid().model();
  EXPECT_NE(own, shared);
  EXPECT_DOUBLE_EQ(own->opt.gravity[2], -5.0);
  EXPECT_NEAR(shared->opt.gravity[2], -9.81, 1e-9);  // the session's model is untouched
  for (int b = 1; b < shared->nbody; ++b) EXPECT_NEAR(own->body_mass[b], 1.25 * shared->body_mass[b], 1e-9) << b;
  // The obstacle stands on the floor, 2 m ahead of the start root along the clip's heading.
  const int g = mj_name2id(own, mjOBJ_GEOM, kFamilyObstacleName);
  ASSERT_GE(g, 0);
  EXPECT_NEAR(own->geom_size[3 * g + 2], 0.15, 1e-6);
  EXPECT_NEAR(own->geom_pos[3 * g + 2], 0.15, 1e-6);
  const Vec3 start = envs.motions().clip(0).body_pos[0];
  EXPECT_NEAR(std::hypot(own->geom_pos[3 * g] - start.x(), own->geom_pos[3 * g + 1] - start.y()), 2.0, 1e-6);
  // The normalized parameters lead the goal.
  const float* goal = &envs.buffers().obs[envs.spec().goal_obs.start];
  EXPECT_NEAR(goal[0], 0.1, 1e-6);
  EXPECT_NEAR(goal[1], 0.5, 1e-6);
  EXPECT_NEAR(envs.buffers().family_params[0], 5.f, 1e-6);
}

TEST(FamilyEnvTest, JointsHaveThePapersTorqueLimitsByGroupScaledByMass) {
  auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 9.81, 9.81}}, 1), Clip("deepmimic_jump"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  EnvBatch& envs = **batch;
  // A family simulates with stable PD, whose limits bound the damping too (ModelForTask).
  EXPECT_EQ(envs.humanoid().options().pd_mode, PdMode::kStablePd);
  const HumanoidSpec& spec = envs.humanoid().spec();
  const double scale = mj_getTotalmass(envs.humanoid().model()) / 61.7;  // Lee et al.'s character: 61.7 kg
  const std::vector<double>& hinges = envs.env(0).family()->torque_limits();
  ASSERT_EQ(static_cast<int>(hinges.size()), envs.humanoid().num_hinges());
  auto limit = [&](const char* body, int axis) { return hinges[3 * (spec.BodyIndex(body) - 1) + axis]; };
  EXPECT_NEAR(limit("L_Hip", 0), 200 * scale, 1e-9);
  EXPECT_NEAR(limit("R_Knee", 1), 150 * scale, 1e-9);
  EXPECT_NEAR(limit("L_Ankle", 2), 90 * scale, 1e-9);
  EXPECT_NEAR(limit("Neck", 0), 50 * scale, 1e-9);
  EXPECT_NEAR(limit("R_Shoulder", 0), 100 * scale, 1e-9);
  EXPECT_NEAR(limit("L_Elbow", 1), 60 * scale, 1e-9);
  EXPECT_NEAR(envs.humanoid().torque_limit()[0], 500, 1e-9) << "tracking keeps PHC's limits";
  // They reach the physics: full displacements saturate some hinges at their limits, none beyond.
  envs.Reset();
  std::vector<float> actions(envs.spec().action_size, 1.f);
  actions[envs.spec().time_warp_action] = 0.f;
  ASSERT_TRUE(envs.Step(actions).ok());
  const int qvel = envs.humanoid().hinge_qvel_start();
  int saturated = 0;
  for (size_t h = 0; h < hinges.size(); ++h) {
    const double torque = std::abs(envs.env(0).data()->qfrc_applied[qvel + h]);
    EXPECT_LE(torque, hinges[h] + 1e-9) << h;
    saturated += torque > hinges[h] - 1e-9;
  }
  EXPECT_GT(saturated, 0);
}

TEST(FamilyEnvTest, DisplacementsAreNotClampedIntoTheJointRanges) {
  // A full displacement reaches past some hinge's range in a family
  // (ActionMapping::clamp_to_joint_range), never in tracking.
  auto count_beyond = [](EnvBatch& envs) {
    std::vector<float> actions(envs.spec().action_size, 1.f);
    if (envs.spec().time_warp_action >= 0) actions[envs.spec().time_warp_action] = 0.f;
    EXPECT_TRUE(envs.Step(actions).ok());
    const mjModel* model = envs.humanoid().model();
    const std::vector<double>& targets = envs.env(0).pd_targets();
    const int first_joint = envs.humanoid().options().fixed_root ? 0 : 1;  // the hinges follow the free joint
    int beyond = 0;
    for (int h = 0; h < envs.humanoid().num_hinges(); ++h) {
      beyond += targets[h] > model->jnt_range[2 * (first_joint + h) + 1] + 1e-9;
    }
    return beyond;
  };
  auto family = EnvBatch::Create(FamilyConfig({{"gravity", 9.81, 9.81}}, 1), Clip("deepmimic_jump"));
  ASSERT_TRUE(family.ok()) << family.status();
  (*family)->Reset();
  EXPECT_GT(count_beyond(**family), 0);
  EnvBatchConfig tracking = FamilyConfig({}, 1);
  auto tracker = EnvBatch::Create(tracking, Clip("deepmimic_jump"));
  ASSERT_TRUE(tracker.ok()) << tracker.status();
  (*tracker)->Reset();
  EXPECT_EQ(count_beyond(**tracker), 0);
}

TEST(FamilyEnvTest, LowerGravityJumpsHigher) {
  auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 4, 14}}, 1), Clip("deepmimic_jump"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  EnvBatch& envs = **batch;
  StartAll(envs, {4.f});
  const double low = RootApex(envs);
  StartAll(envs, {14.f});
  const double high = RootApex(envs);
  EXPECT_GT(low, high + 0.05) << "apex under 4 m/s^2: " << low << ", under 14 m/s^2: " << high;
}

TEST(FamilyEnvTest, JumpHeightPaysOneSpikeAtTheApexAndFitnessAtTheEnd) {
  // Launched at 2.5 m/s the root rises 2.5^2 / (2 g) = 0.32 m above its start.
  auto batch = EnvBatch::Create(FamilyConfig({{"jump_height", 0.5, 1.5}}, 1), Clip("deepmimic_jump"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  EnvBatch& envs = **batch;
  StartAll(envs, {1.2f});
  Launch(envs);
  const std::vector<float> actions = Actions(envs, 0.f);
  const int task_column = static_cast<int>(std::find(envs.spec().reward_terms.begin(), envs.spec().reward_terms.end(),
                                                     "task") - envs.spec().reward_terms.begin());
  int spikes = 0;
  bool ended = false;
  for (int step = 0; step < 200 && !ended; ++step) {
    ASSERT_TRUE(envs.Step(actions).ok());
    const BatchBuffers& out = envs.buffers();
    const float spike = out.spike_reward[0];
    EXPECT_FLOAT_EQ(out.reward_terms[task_column], spike);
    EXPECT_EQ(out.reward_terms[envs.spec().reward_terms.size() - 1], 0.f) << "no energy penalty in a family";
    if (spike > 0) {
      ++spikes;
      EXPECT_LE(spike, kFamilySpikeWeight);
    }
    ended = out.done[0];
    if (ended) {
      EXPECT_GT(out.fitness[0], 0.f);
      EXPECT_LT(out.fitness[0], 1.1f);
      EXPECT_FLOAT_EQ(out.ended_family_params[0], 1.2f);
    }
  }
  EXPECT_TRUE(ended);
  EXPECT_EQ(spikes, 1) << "one flight, one apex";
}

TEST(FamilyEnvTest, FitnessOfTheClipsOwnMotionIsHighAndFallsWithTheError) {
  // Open-loop reference PD on the jump at normal gravity: the motion is the clip's until it falls,
  // so F is high (0.80 here; 0.18 when the errors were summed over the 69 hinges and contacts
  // counted as mismatches). A displacement of 0.5 rad on every hinge scores near 0.
  auto fitness_of = [](float displacement) {
    auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 9.81, 9.81}}, 1), Clip("deepmimic_jump"));
    EXPECT_TRUE(batch.ok()) << batch.status();
    EnvBatch& envs = **batch;
    StartAll(envs, {9.81f});
    std::vector<float> actions = Actions(envs, 0.f);
    for (int a = 0; a < envs.spec().time_warp_action; ++a) actions[a] = displacement;
    for (int step = 0; step < 300; ++step) {
      EXPECT_TRUE(envs.Step(actions).ok());
      if (envs.buffers().done[0]) return static_cast<double>(envs.buffers().fitness[0]);
    }
    ADD_FAILURE() << "the episode did not end";
    return -1.0;
  };
  const double reference = fitness_of(0.f), displaced = fitness_of(0.5f);
  EXPECT_GT(reference, 0.6) << "displaced " << displaced;
  EXPECT_LT(displaced, reference - 0.1) << "reference " << reference << ", displaced " << displaced;
}

TEST(FamilyEnvTest, BadParameterRowsAreRefusedNamingThem) {
  auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 4, 14}}), Clip("deepmimic_jump"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  absl::Status outside = (*batch)->SetFamilyParameters(std::vector<float>{5.f, 20.f});
  EXPECT_EQ(outside.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(outside.message().find("row 1 gravity"), std::string::npos) << outside;
  EXPECT_EQ((*batch)->SetFamilyParameters(std::vector<float>{5.f}).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ((*batch)->SetFamilyParameters(std::vector<float>{5.f, NAN}).code(), absl::StatusCode::kInvalidArgument);
  EnvBatchConfig tracking;
  tracking.num_envs = 1;
  auto plain = EnvBatch::Create(tracking, Clip("deepmimic_jump"));
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ((*plain)->SetFamilyParameters(std::vector<float>{5.f}).code(), absl::StatusCode::kFailedPrecondition);
}

// The distance between two bodies of env 0's simulated character (from its own kinematics).
double BodyDistance(const HumanoidState& state, int a, int b) { return (state.body_pos[a] - state.body_pos[b]).norm(); }

// leg_scale and arm_scale reach the physics and the reference: the env's model has longer limbs,
// its clip is the clip on that skeleton (on the ground, its stride scaled), and the simulated
// character starts on it; the session's own proportions are untouched by a scaled episode.
TEST(FamilyEnvTest, BodyProportionsScaleTheModelAndTheReference) {
  auto batch = EnvBatch::Create(FamilyConfig({{"leg_scale", 0.8, 1.2}, {"arm_scale", 0.8, 1.2}}), Clip("deepmimic_walk"));
  ASSERT_TRUE(batch.ok()) << batch.status();
  const HumanoidModel& base = (*batch)->humanoid();
  const HumanoidSpec& spec = base.spec();
  const int hip = spec.BodyIndex("L_Hip"), knee = spec.BodyIndex("L_Knee"), ankle = spec.BodyIndex("L_Ankle");
  const int shoulder = spec.BodyIndex("R_Shoulder"), elbow = spec.BodyIndex("R_Elbow"), pelvis = 0;
  const MotionClip& original = ShippedClip("deepmimic_walk");
  const double thigh = (original.body_pos[knee] - original.body_pos[hip]).norm();
  const double upper_arm = (original.body_pos[elbow] - original.body_pos[shoulder]).norm();
  const int last = original.num_frames - 1;
  const double stride = (original.body_pos[static_cast<size_t>(last) * original.num_bodies] - original.body_pos[0]).head<2>().norm();
  for (float leg : {0.8f, 1.2f}) {
    StartAll(**batch, {leg, 1.2f});
    const TrackingEnv& env = (*batch)->env(0);
    ASSERT_NE(env.family()->body_model(), nullptr);
    const MotionClip& clip = env.motion();
    EXPECT_NEAR((clip.body_pos[knee] - clip.body_pos[hip]).norm(), leg * thigh, 1e-6);
    EXPECT_NEAR((clip.body_pos[elbow] - clip.body_pos[shoulder]).norm(), 1.2 * upper_arm, 1e-6);
    EXPECT_NEAR(LowestGeomPoint(env.family()->body_model()->spec(), clip, 0), 0.0, 0.02);
    const double scaled_stride = (clip.body_pos[static_cast<size_t>(last) * clip.num_bodies] - clip.body_pos[0]).head<2>().norm();
    EXPECT_NEAR(scaled_stride, leg * stride, 1e-6);
    // The model the physics steps: the knee hangs leg x the thigh below the hip.
    const mjModel* m = env.family()->model();
    const double knee_offset = mju_norm3(m->body_pos + 3 * (knee + 1));
    EXPECT_NEAR(knee_offset, leg * mju_norm3(base.model()->body_pos + 3 * (knee + 1)), 1e-6);
    // The simulated character starts on the scaled reference, read with the scaled skeleton.
    HumanoidState sim;
    sim.Resize(spec.num_bodies(), spec.num_hinges());
    ReadSimulatedState(*env.family()->body_model(), env.data(), &sim);
    EXPECT_NEAR(BodyDistance(sim, hip, knee), leg * thigh, 1e-6);
    EXPECT_NEAR(sim.body_pos[pelvis].z(), clip.body_pos[pelvis].z(), 1e-6);
    EXPECT_NEAR(BodyDistance(sim, knee, ankle) / (original.body_pos[ankle] - original.body_pos[knee]).norm(), leg, 1e-6);
    // Open loop, the scaled walk runs a few steps without blowing up.
    for (int step = 0; step < 5; ++step) ASSERT_TRUE((*batch)->Step(Actions(**batch, 0.f)).ok());
    EXPECT_EQ((*batch)->env(0).physics_resets(), 0);
  }
  // A longer-legged walker stands higher.
  StartAll(**batch, {0.8f, 1.f});
  const double short_pelvis = (*batch)->env(0).motion().body_pos[0].z();
  StartAll(**batch, {1.2f, 1.f});
  EXPECT_GT((*batch)->env(0).motion().body_pos[0].z(), short_pelvis + 0.1);
}

TEST(FamilyEnvTest, SessionsTheServerCannotRunAreRefused) {
  auto two_clips = DefaultMotions()->Subset({"deepmimic_jump", "deepmimic_walk"});
  ASSERT_TRUE(two_clips.ok());
  auto batch = EnvBatch::Create(FamilyConfig({{"gravity", 4, 14}}), std::make_shared<const MotionLibrary>(*two_clips));
  EXPECT_NE(batch.status().message().find("exactly one clip"), std::string::npos) << batch.status();
  EnvBatchConfig absolute = FamilyConfig({{"gravity", 4, 14}});
  absolute.env.action.mode = ActionMode::kAbsolute;
  EXPECT_FALSE(EnvBatch::Create(absolute, Clip("deepmimic_jump")).ok());
  auto tiny = EnvBatch::Create(FamilyConfig({{"leg_scale", 0, 1.2}}), Clip("deepmimic_walk"));
  EXPECT_NE(tiny.status().message().find("leg_scale"), std::string::npos) << tiny.status();
  auto inverted = EnvBatch::Create(FamilyConfig({{"gravity", 14, 4}}), Clip("deepmimic_walk"));
  EXPECT_NE(inverted.status().message().find("inverted"), std::string::npos) << inverted.status();
}

}  // namespace
}  // namespace modskill
