// The task envs (steer, reach, VR tracking): their observation layout, goals, rewards, falls and
// bad settings, without a server.
#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include "server/core/env/base_motion_anchor.h"
#include "server/core/env/episode_end.h"
#include "server/core/env/fall_detection.h"
#include "server/core/env/observation.h"
#include "server/core/env/reach_task.h"
#include "server/core/env/steer_task.h"
#include "server/core/env/strike_task.h"
#include "server/core/sim/mjcf_builder.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

EnvBatchConfig TaskConfig(TaskKind task, int envs = 4) {
  EnvBatchConfig config;
  config.num_envs = envs;
  config.seed = 5;
  config.env.task = task;
  config.env.action.mode = ActionMode::kResidual;
  return config;
}

int ClipIndex(const char* name) {
  const int index = DefaultMotions()->Find(name);
  EXPECT_GE(index, 0) << name;
  return std::max(index, 0);
}

TEST(TaskSpecTest, TaskObservationIsTrackingsOrTheSelfFeaturesThenTheGoal) {
  for (const TaskInfo& task : AllTasks()) {
    auto batch = MakeBatch(TaskConfig(task.kind));
    ASSERT_NE(batch, nullptr) << task.name;
    const EnvSpec& spec = batch->spec();
    EXPECT_EQ(spec.reward_terms, task.reward_terms) << task.name;
    EXPECT_EQ(spec.reward_terms.back(), "energy");
    EXPECT_EQ(batch->buffers().widths.reward_terms, static_cast<int64_t>(task.reward_terms.size()));
    EXPECT_EQ(spec.self_obs_size, 358) << task.name;
    EXPECT_EQ(spec.action_size, 69);
    if (task.kind == TaskKind::kTracking) {
      EXPECT_EQ(spec.obs_size, 934);
      EXPECT_EQ(spec.goal_obs.size, 0);
      continue;
    }
    // Steer, reach and strike observe what tracking does (their base motion as the reference),
    // VR tracking the self features only; the goal follows.
    const int bodies_end = IsGoalTask(task.kind) ? 934 : 358;
    EXPECT_EQ(spec.goal_obs.start, bodies_end) << task.name;
    EXPECT_EQ(spec.goal_obs.size, task.goal_size) << task.name;
    EXPECT_EQ(spec.task_obs_size, bodies_end - 358 + task.goal_size) << task.name;
    EXPECT_EQ(spec.obs_size, bodies_end + task.goal_size);
    int end = 0;
    for (const Slice& part : spec.part_obs) {
      EXPECT_EQ(part.start, end) << task.name;
      end += part.size;
    }
    EXPECT_EQ(end, bodies_end) << task.name << ": the parts tile the bodies' features";
  }
  EXPECT_EQ(TaskInfoOf(TaskKind::kSteer).goal_size, 3);
  EXPECT_EQ(TaskInfoOf(TaskKind::kReach).goal_size, 3);
  EXPECT_EQ(TaskInfoOf(TaskKind::kStrike).goal_size, 15);
  EXPECT_EQ(TaskInfoOf(TaskKind::kVrTracking).goal_size, 72);
}

// A task env's self features are the tracking observation's self features of the same state, so
// the tracker's frozen part controllers read what they were trained on.
TEST(TaskSpecTest, SelfFeaturesEqualTrackingsAndVrGoalIsTrackingsTaskFeatures) {
  auto tracking = MakeBatch(TaskConfig(TaskKind::kTracking, 1));
  auto steer = MakeBatch(TaskConfig(TaskKind::kSteer, 1));
  auto vr = MakeBatch(TaskConfig(TaskKind::kVrTracking, 1));
  ASSERT_TRUE(tracking && steer && vr);
  const int walk = ClipIndex("deepmimic_walk");
  for (EnvBatch* batch : {tracking.get(), steer.get(), vr.get()}) batch->env(0).ResetTo(walk, 7, batch->row(0));
  const std::vector<float> zeros(69, 0.f);
  for (int step = 0; step < 3; ++step) {
    for (EnvBatch* batch : {tracking.get(), steer.get(), vr.get()}) ASSERT_TRUE(batch->Step(zeros).ok());
  }
  const EnvSpec& t = tracking->spec();
  for (EnvBatch* batch : {steer.get(), vr.get()}) {
    const EnvSpec& s = batch->spec();
    for (int body = 0; body < 24; ++body) {
      const int size = body == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody;
      for (int k = 0; k < size; ++k) {
        ASSERT_EQ(batch->buffers().obs[s.body_obs_start[body] + k], tracking->buffers().obs[t.body_obs_start[body] + k])
            << "body " << body << " feature " << k;
      }
    }
  }
  const EnvSpec& v = vr->spec();
  for (int k = 0; k < kNumVrBodies; ++k) {
    const int body = DefaultSpec().BodyIndex(kVrBodies[k]);
    const int self = body == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody;
    for (int f = 0; f < kTaskFeaturesPerBody; ++f) {
      ASSERT_EQ(vr->buffers().obs[v.goal_obs.start + k * kTaskFeaturesPerBody + f],
                tracking->buffers().obs[t.body_obs_start[body] + self + f])
          << kVrBodies[k] << " feature " << f;
    }
  }
}

HumanoidState StandingState() {
  HumanoidState state;
  state.Resize(24, 69);
  ReadReferenceState(DefaultMotions()->clip(ClipIndex("deepmimic_walk")), 0, &state);
  return state;
}

// Right after a reset the character stands on the reference, so the anchored base motion is the
// reference itself: a goal task's body features equal tracking's, reference features included.
TEST(TaskSpecTest, GoalTaskReferenceFeaturesAreTrackingsOnTheReference) {
  auto tracking = MakeBatch(TaskConfig(TaskKind::kTracking, 1));
  auto steer = MakeBatch(TaskConfig(TaskKind::kSteer, 1));
  ASSERT_TRUE(tracking && steer);
  const int walk = ClipIndex("deepmimic_walk");
  for (EnvBatch* batch : {tracking.get(), steer.get()}) batch->env(0).ResetTo(walk, 7, batch->row(0));
  for (int k = 0; k < 934; ++k) {
    ASSERT_NEAR(steer->buffers().obs[k], tracking->buffers().obs[k], 1e-5) << "feature " << k;
  }
}

// The base motion loops on at frame 1 (the clip's own step from 0 to 1 follows its last frame).
TEST(TaskSpecTest, GoalTaskBaseMotionLoopsOnAtFrameOne) {
  auto steer = MakeBatch(TaskConfig(TaskKind::kSteer, 1));
  ASSERT_TRUE(steer);
  const int walk = ClipIndex("deepmimic_walk");
  const int last = DefaultMotions()->clip(walk).num_frames - 1;
  steer->env(0).ResetTo(walk, last - 1, steer->row(0));
  const std::vector<float> zeros(69, 0.f);
  std::vector<int> frames;
  for (int step = 0; step < 3; ++step) {
    ASSERT_TRUE(steer->Step(zeros).ok());
    if (steer->buffers().done[0]) break;
    frames.push_back(steer->buffers().frame[0]);
  }
  EXPECT_EQ(frames, (std::vector<int>{last, 1, 2}));
}

// The anchor carries the next frame onto the character: a target equal to the anchor lands on
// the character's root (x, y) facing its heading, at the clip's own height, and a body's offset
// from the root turns with the heading.
TEST(BaseMotionAnchorTest, CarriesTheClipOntoTheCharactersRootAndHeading) {
  HumanoidState anchor = StandingState(), sim = StandingState(), target = StandingState();
  const Quat turn(Eigen::AngleAxisd(1.2, Vec3::UnitZ()));
  sim.body_pos[0] += Vec3(3.0, -2.0, 0.1);
  sim.body_rot[0] = turn * sim.body_rot[0];
  const Vec3 hand_offset = target.body_pos[23] - target.body_pos[0];
  const Vec3 velocity = target.body_vel[5];
  AnchorToCharacter(anchor, sim, &target);
  EXPECT_NEAR(target.body_pos[0].x(), sim.body_pos[0].x(), 1e-9);
  EXPECT_NEAR(target.body_pos[0].y(), sim.body_pos[0].y(), 1e-9);
  EXPECT_NEAR(target.body_pos[0].z(), anchor.body_pos[0].z(), 1e-9) << "heights stay the clip's";
  EXPECT_NEAR(target.body_rot[0].angularDistance(sim.body_rot[0]), 0.0, 1e-9);
  EXPECT_LT(((target.body_pos[23] - target.body_pos[0]) - turn * hand_offset).norm(), 1e-9);
  EXPECT_LT((target.body_vel[5] - turn * velocity).norm(), 1e-9);
}

// A steered base motion turns toward the goal's bearing by at most the step's turn, never leads
// the character by more than kMaxSteeringLead, and ignores a goal within the dead zone; anchored
// at its heading it stands on the character's root facing that heading.
TEST(BaseMotionAnchorTest, SteeredHeadingTurnsTowardTheGoalWithinItsLead) {
  HumanoidState sim = StandingState();
  sim.body_pos[0] += Vec3(1.0, 2.0, 0.0);
  sim.body_rot[0] = Quat(Eigen::AngleAxisd(0.7, Vec3::UnitZ())) * sim.body_rot[0];
  const double character = HeadingAngle(sim.body_rot[0]);
  auto toward_bearing = [&](double bearing, double distance) -> Vec3 {
    return distance * Vec3(std::cos(character + bearing), std::sin(character + bearing), 0.0) + Vec3(0, 0, 5.0);
  };
  for (const auto& [bearing, distance, expected] :
       {std::tuple{1.0, 2.0, 0.05}, std::tuple{-2.5, 2.0, -0.05}, std::tuple{-0.03, 2.0, -0.03},
        std::tuple{1.0, 0.1, 0.0}}) {
    const double heading = SteerHeading(character, sim, toward_bearing(bearing, distance), 0.05);
    EXPECT_NEAR(std::remainder(heading - character, 2 * M_PI), expected, 1e-12) << "bearing " << bearing;
  }
  double heading = character;
  for (int step = 0; step < 40; ++step) heading = SteerHeading(heading, sim, toward_bearing(2.0, 2.0), 0.05);
  EXPECT_NEAR(std::remainder(heading - character, 2 * M_PI), kMaxSteeringLead, 1e-12) << "the lead is bounded";

  HumanoidState target = StandingState();
  const HumanoidState anchor = StandingState();
  const double anchor_heading = HeadingAngle(anchor.body_rot[0]);
  const Vec3 hand_offset = target.body_pos[23] - target.body_pos[0];
  AnchorToHeading(anchor, sim, character + 0.3, &target);
  EXPECT_NEAR(target.body_pos[0].x(), sim.body_pos[0].x(), 1e-9);
  EXPECT_NEAR(target.body_pos[0].y(), sim.body_pos[0].y(), 1e-9);
  EXPECT_NEAR(std::remainder(HeadingAngle(target.body_rot[0]) - (character + 0.3), 2 * M_PI), 0.0, 1e-9);
  const Quat turn(Eigen::AngleAxisd(character + 0.3 - anchor_heading, Vec3::UnitZ()));
  EXPECT_LT(((target.body_pos[23] - target.body_pos[0]) - turn * hand_offset).norm(), 1e-9);
}

// With a steering rate the steer env's observed base motion starts at the character's heading and
// turns after the first step; the simulation and the goal are the same as without.
TEST(TaskSpecTest, SteeringRateTurnsTheObservedBaseMotion) {
  EnvBatchConfig steered_config = TaskConfig(TaskKind::kSteer, 1);
  steered_config.env.task_settings.steering_rate = 60;
  auto straight = MakeBatch(TaskConfig(TaskKind::kSteer, 1));
  auto steered = MakeBatch(steered_config);
  ASSERT_TRUE(straight && steered);
  const int walk = ClipIndex("deepmimic_walk");
  for (EnvBatch* batch : {straight.get(), steered.get()}) batch->env(0).ResetTo(walk, 7, batch->row(0));
  const EnvSpec& spec = steered->spec();
  for (int k = 0; k < spec.obs_size; ++k) {
    ASSERT_NEAR(steered->buffers().obs[k], straight->buffers().obs[k], 1e-5) << "no turn before the first step, feature " << k;
  }
  const std::vector<float> zeros(69, 0.f);
  for (EnvBatch* batch : {straight.get(), steered.get()}) ASSERT_TRUE(batch->Step(zeros).ok());
  float most = 0;
  for (int k = 0; k < spec.goal_obs.start; ++k) {
    most = std::max(most, std::abs(steered->buffers().obs[k] - straight->buffers().obs[k]));
  }
  EXPECT_GT(most, 1e-3) << "the reference features turned";
  for (int k = spec.goal_obs.start; k < spec.obs_size; ++k) {
    ASSERT_EQ(steered->buffers().obs[k], straight->buffers().obs[k]) << "goal feature " << k;
  }
}

TEST(SteerTaskTest, MovingAlongTheTargetAtItsSpeedWhileFacingItEarnsOne) {
  GoalTaskContext context;
  context.control_dt = 1.0 / 30;
  SteerTask steer(&context);
  std::mt19937_64 rng(11);
  HumanoidState state = StandingState();
  steer.Reset(state, nullptr, rng);
  const Vec3 d = steer.direction();
  EXPECT_NEAR(d.norm(), 1.0, 1e-12);
  EXPECT_EQ(d.z(), 0);
  EXPECT_GE(steer.speed(), 0.5);
  EXPECT_LE(steer.speed(), 3.0);
  // Face the target: yaw the root onto d, then move along d at the target speed for one step.
  state.body_rot[0] = Quat(Eigen::AngleAxisd(std::atan2(d.y(), d.x()), Vec3::UnitZ()));
  state.body_pos[0] += d * steer.speed() * context.control_dt;
  float terms[2];
  steer.Reward(state, nullptr, terms);
  EXPECT_NEAR(terms[0], 0.7, 1e-6);
  EXPECT_NEAR(terms[1], 0.3, 1e-6);
  // The goal in the heading frame is straight ahead.
  float goal[3];
  steer.WriteGoal(state, nullptr, goal);
  EXPECT_NEAR(goal[0], 1.0, 1e-6);
  EXPECT_NEAR(goal[1], 0.0, 1e-6);
  EXPECT_FLOAT_EQ(goal[2], static_cast<float>(steer.speed()));
  // Standing still facing away: the speed error alone, no facing reward.
  state.body_rot[0] = Quat(Eigen::AngleAxisd(std::atan2(-d.y(), -d.x()), Vec3::UnitZ()));
  steer.Reward(state, nullptr, terms);
  EXPECT_NEAR(terms[0], 0.7 * std::exp(-0.25 * steer.speed() * steer.speed()), 1e-6);
  EXPECT_NEAR(terms[1], 0.0, 1e-6);
}

// The facing term takes the root's x axis as forward: the reference walk and run move that way.
TEST(SteerTaskTest, LocomotionClipsMoveAlongTheFacingAxis) {
  for (const char* name : {"deepmimic_walk", "deepmimic_run", "deepmimic_jog"}) {
    const MotionClip& clip = DefaultMotions()->clip(ClipIndex(name));
    HumanoidState a, b;
    a.Resize(24, 69);
    b.Resize(24, 69);
    ReadReferenceState(clip, 0, &a);
    ReadReferenceState(clip, clip.num_frames - 1, &b);
    Vec3 travel = b.body_pos[0] - a.body_pos[0];
    travel.z() = 0;
    const Vec3 facing = HeadingRotation(a.body_rot[0]) * Vec3::UnitX();
    EXPECT_GT(facing.dot(travel.normalized()), 0.8) << name;
  }
}

TEST(SteerTaskTest, GoalsChangeAtTheSettingsInterval) {
  GoalTaskContext context;
  context.control_dt = 1.0 / 30;
  context.settings.min_goal_interval_s = context.settings.max_goal_interval_s = 0.1;  // 3 steps
  SteerTask steer(&context);
  std::mt19937_64 rng(3);
  const HumanoidState state = StandingState();
  steer.Reset(state, nullptr, rng);
  const Vec3 first = steer.direction();
  steer.NextGoal(state, rng);
  steer.NextGoal(state, rng);
  EXPECT_EQ(steer.direction(), first);
  steer.NextGoal(state, rng);
  EXPECT_NE(steer.direction(), first);
}

TEST(ReachTaskTest, TargetsLieInTheBoxAndTheHandAtTheTargetEarnsOne) {
  GoalTaskContext context;
  context.control_dt = 1.0 / 30;
  context.right_hand = DefaultSpec().BodyIndex("R_Hand");
  ReachTask reach(&context);
  std::mt19937_64 rng(4);
  HumanoidState state = StandingState();
  const Quat to_heading = InverseHeadingRotation(state.body_rot[0]);
  for (int draw = 0; draw < 50; ++draw) {
    reach.Reset(state, nullptr, rng);
    Vec3 local = to_heading * (reach.target() - Vec3(state.body_pos[0].x(), state.body_pos[0].y(), 0));
    EXPECT_LE(std::abs(local.x()), 1.0 + 1e-9);
    EXPECT_LE(std::abs(local.y()), 1.0 + 1e-9);
    EXPECT_GE(local.z(), 0.0);
    EXPECT_LE(local.z(), 2.0);
    float goal[3];
    reach.WriteGoal(state, nullptr, goal);
    const Vec3 expected = to_heading * (reach.target() - state.body_pos[0]);
    EXPECT_NEAR(goal[2], expected.z(), 1e-5);
  }
  float terms[1];
  state.body_pos[context.right_hand] = reach.target();
  reach.Reward(state, nullptr, terms);
  EXPECT_FLOAT_EQ(terms[0], 1.f);
  state.body_pos[context.right_hand] = reach.target() + Vec3(0, 0, 1);
  reach.Reward(state, nullptr, terms);
  EXPECT_NEAR(terms[0], std::exp(-5.0), 1e-7);
}

// A smaller box elsewhere (a curriculum's near targets, or a probe's one target) holds every
// draw, and the draws fill it rather than sit at its centre.
TEST(ReachTaskTest, TargetsFollowTheSettingsBox) {
  GoalTaskContext context;
  context.control_dt = 1.0 / 30;
  context.right_hand = DefaultSpec().BodyIndex("R_Hand");
  context.settings.reach_box_size = 0.4;
  context.settings.reach_center[0] = 0.5;
  context.settings.reach_center[1] = -0.3;
  context.settings.reach_center[2] = 1.2;
  ReachTask reach(&context);
  std::mt19937_64 rng(5);
  const HumanoidState state = StandingState();
  const Quat to_heading = InverseHeadingRotation(state.body_rot[0]);
  Vec3 low = Vec3::Constant(1e9), high = Vec3::Constant(-1e9);
  for (int draw = 0; draw < 200; ++draw) {
    reach.Reset(state, nullptr, rng);
    const Vec3 local = to_heading * (reach.target() - Vec3(state.body_pos[0].x(), state.body_pos[0].y(), 0));
    low = low.cwiseMin(local);
    high = high.cwiseMax(local);
  }
  const Vec3 center(0.5, -0.3, 1.2);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GE(low[axis], center[axis] - 0.2 - 1e-9) << axis;
    EXPECT_LE(high[axis], center[axis] + 0.2 + 1e-9) << axis;
    EXPECT_GT(high[axis] - low[axis], 0.3) << axis;
  }
}

// The strike target stands in front at rest, scores 0 standing and 1 lying, and fails the
// episode when a body it does not allow touches it.
TEST(StrikeTaskTest, TargetStandsInFrontAndOnlyTheRightArmMayTouchIt) {
  auto batch = MakeBatch(TaskConfig(TaskKind::kStrike, 1));
  ASSERT_NE(batch, nullptr);
  const mjModel* model = batch->humanoid().model();
  const int joint = mj_name2id(model, mjOBJ_JOINT, kStrikeTargetName);
  ASSERT_GE(joint, 0) << "a strike session's model has the target";
  const int qpos = model->jnt_qposadr[joint];
  TrackingEnv& env = batch->env(0);
  mjData* data = env.mutable_data();
  GoalTaskContext context;
  context.target_qpos = qpos;
  context.target_qvel = model->jnt_dofadr[joint];
  context.target_geom = mj_name2id(model, mjOBJ_GEOM, kStrikeTargetName);
  context.may_touch_target.assign(model->ngeom, 0);
  const int hand = mj_name2id(model, mjOBJ_GEOM, "R_Hand");
  ASSERT_GE(hand, 0);
  context.may_touch_target[hand] = 1;
  context.may_touch_target[mj_name2id(model, mjOBJ_GEOM, "floor")] = 1;
  StrikeTask strike(&context);
  std::mt19937_64 rng(8);
  for (int draw = 0; draw < 20; ++draw) {
    env.ResetTo(ClipIndex("deepmimic_walk"), 0, batch->row(0));
    HumanoidState sim;
    sim.Resize(24, 69);
    ReadSimulatedState(batch->humanoid(), data, &sim);
    strike.Reset(sim, data, rng);
    Vec3 offset(data->qpos[qpos] - sim.body_pos[0].x(), data->qpos[qpos + 1] - sim.body_pos[0].y(), 0);
    EXPECT_GE(offset.norm(), StrikeTask::kMinDistance - 1e-9);
    EXPECT_LE(offset.norm(), StrikeTask::kMaxDistance + 1e-9);
    EXPECT_GE((HeadingRotation(sim.body_rot[0]) * Vec3::UnitX()).dot(offset), -1e-9) << "in front";
    float goal[15];
    strike.WriteGoal(sim, data, goal);
    EXPECT_NEAR(Vec3(goal[0], goal[1], 0).norm(), offset.norm(), 1e-4);
    for (int k = 9; k < 15; ++k) EXPECT_EQ(goal[k], 0.f) << "at rest";
    // A steered base motion aims beside the target, at its left as seen from the root, so the
    // right hand meets it.
    const Vec3 aim = strike.GoalBearing(sim, data);
    const Vec3 beside = Vec3(aim.x(), aim.y(), 0) - offset;
    EXPECT_NEAR(beside.norm(), StrikeTask::kHandOffset, 1e-9);
    EXPECT_NEAR(beside.dot(offset), 0.0, 1e-9);
    EXPECT_GT(offset.cross(beside).z(), 0.0) << "to the left";
    float terms[2];
    strike.Reward(sim, data, terms);
    EXPECT_NEAR(terms[0], 0.f, 1e-6) << "standing";
    EXPECT_GE(terms[1], 0.f);
    EXPECT_LE(terms[1], static_cast<float>(StrikeTask::kApproachWeight));
  }

  // The approach term: walking straight at a target 2 m ahead pays exp(-4 (1 - v)^2) of its weight,
  // walking away pays nothing, standing within reach pays all of it.
  HumanoidState walking = StandingState();
  walking.body_vel[0] = HeadingRotation(walking.body_rot[0]) * Vec3(0.6, 0, 0.1);
  const Vec3 ahead = HeadingRotation(walking.body_rot[0]) * Vec3::UnitX();
  auto place_at = [&](const Vec3& p) {
    data->qpos[qpos] = p.x();
    data->qpos[qpos + 1] = p.y();
    data->qpos[qpos + 3] = 1;
    data->qpos[qpos + 4] = data->qpos[qpos + 5] = data->qpos[qpos + 6] = 0;
  };
  float terms[2];
  place_at(walking.body_pos[0] + 2 * ahead);
  strike.Reward(walking, data, terms);
  EXPECT_NEAR(terms[1], StrikeTask::kApproachWeight * std::exp(-4 * 0.4 * 0.4), 1e-6);
  place_at(walking.body_pos[0] - 2 * ahead);
  strike.Reward(walking, data, terms);
  EXPECT_EQ(terms[1], 0.f) << "walking away";
  place_at(walking.body_pos[0] + 0.8 * ahead);
  strike.Reward(walking, data, terms);
  EXPECT_FLOAT_EQ(terms[1], StrikeTask::kApproachWeight) << "within reach";

  // Lying on its side, far away: the full reward.
  place_at(walking.body_pos[0] - 2 * ahead);
  const Quat lying(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitX()));
  data->qpos[qpos + 3] = lying.w();
  data->qpos[qpos + 4] = lying.x();
  data->qpos[qpos + 5] = lying.y();
  data->qpos[qpos + 6] = lying.z();
  strike.Reward(walking, data, terms);
  EXPECT_NEAR(terms[0], StrikeTask::kTipWeight, 1e-6);
  EXPECT_FLOAT_EQ(terms[1], StrikeTask::kApproachWeight) << "once it is down";
  // Standing where the pelvis is: the torso touches it.
  const Quat upright = Quat::Identity();
  data->qpos[qpos + 3] = upright.w();
  data->qpos[qpos + 4] = data->qpos[qpos + 5] = data->qpos[qpos + 6] = 0;
  data->qpos[qpos] = data->qpos[0];
  data->qpos[qpos + 1] = data->qpos[1];
  mj_forward(model, data);
  EXPECT_TRUE(strike.Failed(data));
  // The same contacts with every geom allowed: no failure (only the listed geoms may touch).
  GoalTaskContext permissive = context;
  permissive.may_touch_target.assign(model->ngeom, 1);
  EXPECT_FALSE(StrikeTask(&permissive).Failed(data));
  // Far from everything: nothing touches it.
  data->qpos[qpos] = data->qpos[0] + 10;
  mj_forward(model, data);
  EXPECT_FALSE(strike.Failed(data));
  // A target flown far away is lost.
  data->qpos[qpos] = data->qpos[0] + 50;
  mj_forward(model, data);
  EXPECT_TRUE(strike.Failed(data));
}

TEST(FallDetectionTest, StandingIsNoFallLyingIs) {
  auto batch = MakeBatch(TaskConfig(TaskKind::kSteer, 1));
  ASSERT_NE(batch, nullptr);
  FallDetector detector(batch->humanoid());
  TrackingEnv& env = batch->env(0);
  env.ResetTo(ClipIndex("deepmimic_walk"), 0, batch->row(0));
  mjData* data = env.mutable_data();
  const mjModel* model = batch->humanoid().model();
  mj_forward(model, data);
  HumanoidState state;
  state.Resize(24, 69);
  ReadSimulatedState(batch->humanoid(), data, &state);
  EXPECT_FALSE(detector.Fallen(data, state));
  // Lying on the back, 0.1 m above the floor: the torso touches it and the root is low.
  data->qpos[2] = 0.12;
  const Quat lying(Eigen::AngleAxisd(M_PI / 2, Vec3::UnitY()));
  data->qpos[3] = lying.w();
  data->qpos[4] = lying.x();
  data->qpos[5] = lying.y();
  data->qpos[6] = lying.z();
  mj_forward(model, data);
  ReadSimulatedState(batch->humanoid(), data, &state);
  EXPECT_TRUE(detector.Fallen(data, state));
}

// A limp humanoid (absolute mode, all targets at the offsets, which is not a standing pose)
// falls; its episode ends as a failure, not a truncation, and the row restarts.
TEST(TaskEnvTest, StepsFallAndTruncate) {
  EnvBatchConfig config = TaskConfig(TaskKind::kSteer, 4);
  config.env.max_episode_steps = 400;
  config.env.action.mode = ActionMode::kAbsolute;
  auto limp = MakeBatch(config);
  ASSERT_NE(limp, nullptr);
  limp->Reset();
  const std::vector<float> zeros(4 * 69, 0.f);
  int falls = 0, truncations = 0;
  for (int step = 0; step < 150; ++step) {
    ASSERT_TRUE(limp->Step(zeros).ok());
    for (int i = 0; i < 4; ++i) {
      falls += limp->buffers().done[i] && !limp->buffers().truncated[i];
      truncations += limp->buffers().truncated[i];
      // Why it ended rides along: a fall here; nothing while the episode goes on.
      EXPECT_EQ(limp->buffers().end_cause[i],
                static_cast<uint8_t>(limp->buffers().done[i] ? EpisodeEnd::kFall : EpisodeEnd::kNone));
      const float* terms = &limp->buffers().reward_terms[i * 3];
      EXPECT_GE(terms[0], 0.f);
      EXPECT_LE(terms[0] + terms[1], 1.f + 1e-6f);
      EXPECT_NEAR(limp->buffers().reward[i], terms[0] + terms[1] + terms[2], 1e-5);
    }
  }
  EXPECT_GT(falls, 0);
  EXPECT_EQ(truncations, 0);
  // With a step limit of 2, walking open loop, every episode is truncated at step 2.
  config.env.max_episode_steps = 2;
  config.env.action.mode = ActionMode::kResidual;
  auto walk = DefaultMotions()->Subset({"deepmimic_walk"});
  ASSERT_TRUE(walk.ok());
  auto short_episodes = MakeBatch(config, std::make_shared<const MotionLibrary>(*std::move(walk)));
  ASSERT_NE(short_episodes, nullptr);
  short_episodes->Reset();
  ASSERT_TRUE(short_episodes->Step(zeros).ok());
  for (int i = 0; i < 4; ++i) EXPECT_FALSE(short_episodes->buffers().done[i]);
  ASSERT_TRUE(short_episodes->Step(zeros).ok());
  for (int i = 0; i < 4; ++i) {
    EXPECT_TRUE(short_episodes->buffers().done[i] && short_episodes->buffers().truncated[i]);
    EXPECT_EQ(short_episodes->buffers().end_cause[i], static_cast<uint8_t>(EpisodeEnd::kTime));
  }
}

// A strike batch builds its own model with the target; its envs step, reset the target with
// every episode and keep the tracking model's humanoid indices.
TEST(TaskEnvTest, StrikeEpisodesStepAndRestartTheTarget) {
  auto batch = MakeBatch(TaskConfig(TaskKind::kStrike, 3));
  ASSERT_NE(batch, nullptr);
  EXPECT_EQ(batch->humanoid().model()->nq, 7 + 69 + 7);
  batch->Reset();
  const std::vector<float> zeros(3 * 69, 0.f);
  int episodes = 0;
  for (int step = 0; step < 90; ++step) {
    ASSERT_TRUE(batch->Step(zeros).ok());
    for (int i = 0; i < 3; ++i) {
      const float* terms = &batch->buffers().reward_terms[i * 3];
      EXPECT_GE(terms[0], 0.f);
      EXPECT_LE(terms[0], static_cast<float>(StrikeTask::kTipWeight));
      EXPECT_GE(terms[1], 0.f);
      EXPECT_LE(terms[1], static_cast<float>(StrikeTask::kApproachWeight));
      episodes += batch->buffers().done[i];
      // The goal's target stands within reach of a new episode's start or is being played with.
      const float* goal = &batch->buffers().obs[i * batch->spec().obs_size + batch->spec().goal_obs.start];
      EXPECT_LT(std::hypot(goal[0], goal[1]), StrikeTask::kLostDistance);
    }
  }
  EXPECT_EQ(batch->physics_resets(), 0);
  EXPECT_GT(episodes, 0) << "open-loop walking falls or bumps into the target within 3 s";
}

// A strike episode whose torso walks into the target ends as the task's own failure, not a fall.
TEST(TaskEnvTest, StrikeContactEndsAsTheTasksFailure) {
  auto batch = MakeBatch(TaskConfig(TaskKind::kStrike, 1));
  ASSERT_NE(batch, nullptr);
  batch->Reset();
  const mjModel* model = batch->humanoid().model();
  const int qpos = model->jnt_qposadr[mj_name2id(model, mjOBJ_JOINT, kStrikeTargetName)];
  mjData* data = batch->env(0).mutable_data();
  // The target where the pelvis is, upright: the torso touches it in the first step.
  data->qpos[qpos] = data->qpos[0];
  data->qpos[qpos + 1] = data->qpos[1];
  ASSERT_TRUE(batch->Step(std::vector<float>(69, 0.f)).ok());
  EXPECT_TRUE(batch->buffers().done[0]);
  EXPECT_FALSE(batch->buffers().truncated[0]);
  EXPECT_EQ(batch->buffers().end_cause[0], static_cast<uint8_t>(EpisodeEnd::kTask));
}

TEST(TaskSettingsTest, OutOfRangeSettingsNameTheField) {
  struct Case {
    TaskSettings settings;
    const char* field;
  };
  TaskSettings speed, inverted, interval, long_interval, nan, no_box, huge_box, underground, far, nan_center,
      backward_steering, fast_steering;
  speed.min_speed = -1;
  inverted.max_speed = 0.1;
  interval.min_goal_interval_s = 0;
  long_interval.max_goal_interval_s = 4000;
  nan.max_speed = std::nan("");
  no_box.reach_box_size = 0;
  huge_box.reach_box_size = 5;
  underground.reach_center[2] = 0.5;  // the 2 m box would reach 0.5 m below the floor
  far.reach_center[0] = 2.5;
  nan_center.reach_center[1] = std::nan("");
  backward_steering.steering_rate = -10;
  fast_steering.steering_rate = 1000;
  for (const Case& c :
       {Case{speed, "min_speed"}, Case{inverted, "max_speed"}, Case{interval, "min_goal_interval_s"},
        Case{long_interval, "max_goal_interval_s"}, Case{nan, "max_speed"}, Case{no_box, "reach_box_size"},
        Case{huge_box, "reach_box_size"}, Case{underground, "reach_center_z"}, Case{far, "reach_center_x"},
        Case{nan_center, "reach_center_y"}, Case{backward_steering, "steering_rate"},
        Case{fast_steering, "steering_rate"}}) {
    const absl::Status status = c.settings.Validate();
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << c.field;
    EXPECT_NE(status.message().find(c.field), std::string::npos) << status;
  }
  EXPECT_TRUE(TaskSettings().Validate().ok());
  auto unknown = ParseTask("sterr");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.status().message().find("sterr"), std::string::npos);
  EXPECT_NE(unknown.status().message().find("steer"), std::string::npos);
  EnvBatchConfig config = TaskConfig(TaskKind::kReach, 1);
  config.env.task_settings.min_speed = 20;
  auto batch = EnvBatch::Create(config, DefaultMotions());
  ASSERT_FALSE(batch.ok());
  EXPECT_NE(batch.status().message().find("min_speed"), std::string::npos);
}

}  // namespace
}  // namespace modskill
