// The humanoid: skeleton numbers, generated MJCF, forward kinematics and PD control.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"

#include "server/core/env/humanoid_state.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/pd_controller.h"
#include "server/core/util/data_paths.h"
#include "tests/test_files.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

TEST(HumanoidSpecTest, MatchesTheSkeletonFile) {
  const HumanoidSpec& spec = DefaultSpec();
  ASSERT_EQ(spec.num_bodies(), 24);
  EXPECT_EQ(spec.num_hinges(), 69);
  EXPECT_EQ(spec.body(0).name, "Pelvis");
  EXPECT_EQ(spec.body(23).name, "R_Hand");
  EXPECT_EQ(spec.body(spec.BodyIndex("L_Knee")).parent, spec.BodyIndex("L_Hip"));
  EXPECT_NEAR(spec.TotalMass(), 71.791, 0.01);
  EXPECT_EQ(spec.body(spec.BodyIndex("L_Hip")).kp, 800);
  EXPECT_EQ(spec.body(spec.BodyIndex("Chest")).kd, 100);
  EXPECT_EQ(spec.body(spec.BodyIndex("R_Wrist")).kp, 300);
}

// The JSON carries its own z-up rest positions, computed independently of our offsets chain.
TEST(HumanoidSpecTest, ZeroPoseForwardKinematicsReproducesRestPositions) {
  std::ifstream in(DataPath("skeleton/smpl24_skeleton.json"));
  const nlohmann::json json = nlohmann::json::parse(in);
  const std::vector<Vec3> rest = DefaultSpec().RestPositions();
  for (int b = 0; b < 24; ++b) {
    const auto& expected = json["bodies"][b]["rest_pos_rel_pelvis_zup"];
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(rest[b][k], expected[k].get<double>(), 1e-4) << b;
  }
  // The same through MuJoCo: the compiled model at qpos0 with the pelvis at the origin.
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  ASSERT_TRUE(humanoid.ok()) << humanoid.status();
  const mjModel* m = (*humanoid)->model();
  mjData* d = mj_makeData(m);
  d->qpos[2] = 0;
  mj_kinematics(m, d);
  for (int b = 0; b < 24; ++b) {
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(d->xpos[3 * (b + 1) + k], rest[b][k], 1e-9) << b;
  }
  // MuJoCo's masses from the generated geoms match the skeleton file.
  double mass = 0;
  for (int b = 1; b < m->nbody; ++b) mass += m->body_mass[b];
  EXPECT_NEAR(mass, json["total_mass_kg"].get<double>(), 0.01);
  mj_deleteData(d);
}

TEST(HumanoidSpecTest, ClipForwardKinematicsMatchesMujocoForRandomPoses) {
  const HumanoidSpec& spec = DefaultSpec();
  MotionClip clip;
  clip.name = "random";
  clip.num_frames = 2;
  clip.num_bodies = 24;
  clip.root_pos = {Vec3(0.1, -0.2, 1.0), Vec3(0.1, -0.2, 1.0)};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-0.6, 0.6);
  for (int f = 0; f < 2; ++f) {
    for (int b = 0; b < 24; ++b) clip.local_rot.push_back(QuatFromIntrinsicXyz(angle(rng), angle(rng), angle(rng)));
  }
  ASSERT_TRUE(ComputeClipKinematics(spec, &clip).ok());
  auto humanoid = HumanoidModel::Create(spec, PhysicsOptions());
  ASSERT_TRUE(humanoid.ok());
  mjData* d = mj_makeData((*humanoid)->model());
  SetSimulationToReference(**humanoid, clip, 0, d);
  // MuJoCo's own kinematics of that state against the clip's (ours, computed without MuJoCo).
  mj_forward((*humanoid)->model(), d);
  for (int b = 0; b < 24; ++b) {
    const int id = b + 1;
    const Vec3 pos(d->xpos[3 * id], d->xpos[3 * id + 1], d->xpos[3 * id + 2]);
    const Quat rot(d->xquat[4 * id], d->xquat[4 * id + 1], d->xquat[4 * id + 2], d->xquat[4 * id + 3]);
    mjtNum velocity[6];
    mj_objectVelocity((*humanoid)->model(), d, mjOBJ_XBODY, id, velocity, 0);
    EXPECT_LT((pos - clip.body_pos[b]).norm(), 1e-9) << b;
    EXPECT_LT(RotationAngle(rot * clip.body_rot[b].conjugate()), 1e-6) << b;
    EXPECT_LT((Vec3(velocity[3], velocity[4], velocity[5]) - clip.body_vel[b]).norm(), 1e-6) << b;
    EXPECT_LT((Vec3(velocity[0], velocity[1], velocity[2]) - clip.body_ang_vel[b]).norm(), 1e-6) << b;
  }
  // And the simulated-state reader (the step loop's forward kinematics) against MuJoCo after
  // real stepping, with contacts and nonzero velocities.
  std::vector<double> targets(69, 0.3);
  PdController pd(**humanoid);
  for (int s = 0; s < 5; ++s) pd.Step(targets.data(), d);
  mj_forward((*humanoid)->model(), d);
  HumanoidState state;
  state.Resize(24, 69);
  ReadSimulatedState(**humanoid, d, &state);
  for (int b = 0; b < 24; ++b) {
    const int id = b + 1;
    mjtNum velocity[6];
    mj_objectVelocity((*humanoid)->model(), d, mjOBJ_XBODY, id, velocity, 0);
    EXPECT_LT((state.body_pos[b] - Vec3(d->xpos[3 * id], d->xpos[3 * id + 1], d->xpos[3 * id + 2])).norm(), 1e-9) << b;
    EXPECT_LT((state.body_vel[b] - Vec3(velocity[3], velocity[4], velocity[5])).norm(), 1e-6) << b;
    EXPECT_LT((state.body_ang_vel[b] - Vec3(velocity[0], velocity[1], velocity[2])).norm(), 1e-6) << b;
  }
  mj_deleteData(d);
}

TEST(HumanoidSpecTest, ScalingChangesLimbsAndStillCompiles) {
  BodyScaling scaling;
  scaling.length_by_body["L_Hip"] = 1.3;  // a longer left thigh
  scaling.radius_by_body["L_Hip"] = 1.2;
  auto scaled = DefaultSpec().Scaled(scaling);
  ASSERT_TRUE(scaled.ok()) << scaled.status();
  const int knee = DefaultSpec().BodyIndex("L_Knee");
  EXPECT_NEAR(scaled->body(knee).offset.norm(), 1.3 * DefaultSpec().body(knee).offset.norm(), 1e-12);
  EXPECT_GT(scaled->TotalMass(), DefaultSpec().TotalMass());
  auto humanoid = HumanoidModel::Create(*scaled, PhysicsOptions());
  EXPECT_TRUE(humanoid.ok()) << humanoid.status();
  EXPECT_NE((*humanoid)->mjcf().find("L_Hip"), std::string::npos);

  BodyScaling bad;
  bad.length_by_body["Tail"] = 2.0;
  auto rejected = DefaultSpec().Scaled(bad);
  ASSERT_FALSE(rejected.ok());
  EXPECT_NE(rejected.status().message().find("Tail"), std::string::npos);
  bad = BodyScaling();
  bad.global_length = 0;
  EXPECT_FALSE(DefaultSpec().Scaled(bad).ok());
}

TEST(HumanoidSpecTest, BadSkeletonFilesAreErrors) {
  const std::string dir = ProcessTempDir("humanoid_test");
  auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir + "/" + name) << text;
    return dir + "/" + name;
  };
  EXPECT_FALSE(HumanoidSpec::LoadFromJson(dir + "/missing.json").ok());
  auto not_json = HumanoidSpec::LoadFromJson(write("bad1.json", "{ not json"));
  ASSERT_FALSE(not_json.ok());
  EXPECT_NE(not_json.status().message().find("bad1.json"), std::string::npos);
  auto no_bodies = HumanoidSpec::LoadFromJson(write("bad2.json", "{\"x\": 1}"));
  ASSERT_FALSE(no_bodies.ok());
  EXPECT_NE(no_bodies.status().message().find("bodies"), std::string::npos);
  auto bad_geom = HumanoidSpec::LoadFromJson(write(
      "bad3.json",
      R"({"bodies": [{"name": "Pelvis", "parent": -1, "offset_yup": [0, 0, 0],
          "geom": {"type": "cone", "size": [0.1], "density": 1000, "pos_yup": [0, 0, 0]}}]})"));
  ASSERT_FALSE(bad_geom.ok());
  EXPECT_NE(bad_geom.status().message().find("cone"), std::string::npos);
}

// Hanging from a welded pelvis, the PD holds reference poses against gravity for one second.
// Stated bound: mean hinge error under 1 degree, mean body error under 30 mm (measured with
// bench/pd_hold_bench: 0.26 degrees and 14 mm).
TEST(PdControllerTest, HoldsReferencePosesForOneSecond) {
  PhysicsOptions options;
  options.fixed_root = true;
  options.fixed_root_height = 2.5;
  auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
  ASSERT_TRUE(humanoid.ok());
  const mjModel* m = (*humanoid)->model();
  mjData* d = mj_makeData(m);
  PdController pd(**humanoid);
  const MotionLibrary& motions = *DefaultMotions();
  HumanoidState state;
  state.Resize(24, 69);
  for (const char* name : {"deepmimic_walk", "deepmimic_punch", "cmu_02_01"}) {
    const int c = motions.Find(name);
    ASSERT_GE(c, 0) << name;
    const MotionClip& clip = motions.clip(c);
    const int frame = clip.num_frames / 2;
    SetSimulationToReference(**humanoid, clip, frame, d);
    mju_zero(d->qvel, m->nv);
    std::vector<double> targets(69);
    for (int h = 0; h < 69; ++h) {
      targets[h] = std::clamp(clip.dof_pos[frame * 69 + h], m->jnt_range[2 * h], m->jnt_range[2 * h + 1]);
    }
    for (int s = 0; s < 30; ++s) pd.Step(targets.data(), d);
    mj_forward(m, d);
    ReadSimulatedState(**humanoid, d, &state);
    double joint_error = 0;
    for (int h = 0; h < 69; ++h) joint_error += std::abs(state.dof_pos[h] - targets[h]) / 69;
    EXPECT_LT(joint_error * 180 / M_PI, 1.0) << name;
    // Body positions against the forward kinematics of the targets.
    std::vector<Quat> rot(24);
    std::vector<Vec3> pos(24);
    rot[0] = state.body_rot[0];
    pos[0] = state.body_pos[0];
    double body_error = 0;
    for (int b = 1; b < 24; ++b) {
      const int p = DefaultSpec().body(b).parent;
      rot[b] = rot[p] * HingeRotation(targets[3 * (b - 1)], targets[3 * (b - 1) + 1], targets[3 * (b - 1) + 2]);
      pos[b] = pos[p] + rot[p] * DefaultSpec().body(b).offset;
      body_error += (state.body_pos[b] - pos[b]).norm() / 23;
    }
    EXPECT_LT(body_error, 0.030) << name;
  }
  mj_deleteData(d);
}

TEST(PdControllerTest, StablePdModeAlsoHoldsAndBothModesParse) {
  EXPECT_EQ(*ParsePdMode("stable_pd"), PdMode::kStablePd);
  EXPECT_EQ(*ParsePdMode("position_implicit"), PdMode::kPositionImplicitDamping);
  auto bad = ParsePdMode("explicit");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("pd_mode"), std::string::npos);

  PhysicsOptions options;
  options.fixed_root = true;
  options.fixed_root_height = 2.5;
  options.pd_mode = PdMode::kStablePd;
  auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
  ASSERT_TRUE(humanoid.ok());
  const mjModel* m = (*humanoid)->model();
  mjData* d = mj_makeData(m);
  PdController pd(**humanoid);
  std::vector<double> targets(69, 0.0);
  targets[3 * (DefaultSpec().BodyIndex("L_Elbow") - 1) + 1] = -1.0;  // bend the left elbow
  for (int s = 0; s < 30; ++s) pd.Step(targets.data(), d);
  // Stable PD droops more under gravity than the implicit mode (bench/pd_hold_bench).
  double mean_error = 0;
  for (int h = 0; h < 69; ++h) {
    EXPECT_NEAR(d->qpos[h], targets[h], 0.1) << h;
    mean_error += std::abs(d->qpos[h] - targets[h]) / 69;
  }
  EXPECT_LT(mean_error, 0.02);
  mj_deleteData(d);
}

// --pd_gain_scale multiplies every servo's kp and kd, in the compiled model as in what
// PdController reads, and a stiffer arm droops less under gravity.
TEST(PdControllerTest, GainScaleStiffensEveryServo) {
  const int elbow_hinge = 3 * (DefaultSpec().BodyIndex("L_Elbow") - 1) + 1;
  auto droop = [&](double scale, std::shared_ptr<const HumanoidModel>* out) {
    PhysicsOptions options;
    options.fixed_root = true;
    options.fixed_root_height = 2.5;
    options.pd_gain_scale = scale;
    auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
    EXPECT_TRUE(humanoid.ok()) << humanoid.status();
    *out = *humanoid;
    const mjModel* m = (*humanoid)->model();
    mjData* d = mj_makeData(m);
    PdController pd(**humanoid);
    std::vector<double> targets(69, 0.0);
    targets[3 * (DefaultSpec().BodyIndex("L_Shoulder") - 1) + 2] = -1.5;  // the arm held out sideways
    for (int s = 0; s < 30; ++s) pd.Step(targets.data(), d);
    double error = 0;
    for (int h = 0; h < 69; ++h) error += std::abs(d->qpos[(*humanoid)->hinge_qpos_start() + h] - targets[h]);
    mj_deleteData(d);
    return error;
  };
  std::shared_ptr<const HumanoidModel> base, stiff;
  const double base_droop = droop(1.0, &base);
  const double stiff_droop = droop(2.0, &stiff);
  for (int h = 0; h < 69; ++h) {
    EXPECT_DOUBLE_EQ(stiff->kp()[h], 2 * base->kp()[h]) << h;
    EXPECT_DOUBLE_EQ(stiff->kd()[h], 2 * base->kd()[h]) << h;
    EXPECT_NEAR(stiff->model()->actuator_gainprm[h * mjNGAIN], 2 * base->model()->actuator_gainprm[h * mjNGAIN], 1e-6);
  }
  const int dof = stiff->hinge_qvel_start() + elbow_hinge;
  EXPECT_NEAR(stiff->model()->dof_damping[dof], 2 * base->model()->dof_damping[dof], 1e-6);
  EXPECT_GT(base_droop, 0.0);
  EXPECT_LT(stiff_droop, 0.7 * base_droop);

  for (double bad : {0.0, -1.0, 101.0, std::nan("")}) {
    PhysicsOptions options;
    options.pd_gain_scale = bad;
    auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
    ASSERT_FALSE(humanoid.ok()) << bad;
    EXPECT_NE(humanoid.status().message().find("pd_gain_scale"), std::string::npos) << humanoid.status();
  }
}

// The physics rate is the control rate times the substeps; a count outside [1, 100] is refused
// by name, whether it comes from the server's flag or from code.
TEST(HumanoidModelTest, SubstepsOutsideTheirRangeAreRefused) {
  for (int bad : {0, -1, 101}) {
    PhysicsOptions options;
    options.substeps = bad;
    auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
    ASSERT_FALSE(humanoid.ok()) << bad;
    EXPECT_EQ(humanoid.status().message(), absl::StrCat("substeps: ", bad, " outside [1, 100]"));
  }
  for (int good : {1, 100}) {
    PhysicsOptions options;
    options.substeps = good;
    auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
    ASSERT_TRUE(humanoid.ok()) << humanoid.status();
    // The MJCF carries the timestep to 8 decimals.
    EXPECT_NEAR((*humanoid)->model()->opt.timestep, 1.0 / (30.0 * good), 5e-9);
  }
}

// A family's torque limits (FamilyTorqueLimits: about 170 N*m at the knee) bound the whole PD
// torque under stable PD, damping included. A position servo's damping is MuJoCo joint damping
// outside the actuator's range: against a 170 N*m limit its kd 80 caps the knee's extension at
// 170 / 80 = 2.1 rad/s, too slow to push off for a jump (env_batch.cc's ModelForTask).
TEST(PdControllerTest, StablePdCountsDampingAgainstTheTorqueLimit) {
  constexpr double kLimit = 170;
  const int knee = DefaultSpec().BodyIndex("L_Knee");
  const int hinge = 3 * (knee - 1);  // the knee flexes about its first hinge axis
  const double kd = DefaultSpec().body(knee).kd;
  auto fastest_extension = [&](PdMode mode) {
    PhysicsOptions options;
    options.fixed_root = true;
    options.fixed_root_height = 2.5;
    options.pd_mode = mode;
    auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
    EXPECT_TRUE(humanoid.ok());
    mjModel* m = mj_copyModel(nullptr, (*humanoid)->model());
    for (int a = 0; a < m->nu; ++a) {
      m->actuator_forcerange[2 * a] = -kLimit;
      m->actuator_forcerange[2 * a + 1] = kLimit;
    }
    const std::vector<double> limits(69, kLimit);
    PdController pd(**humanoid);
    pd.UseModel(m);
    pd.UseTorqueLimits(&limits);
    mjData* d = mj_makeData(m);
    const int qpos = (*humanoid)->hinge_qpos_start() + hinge, qvel = (*humanoid)->hinge_qvel_start() + hinge;
    d->qpos[qpos] = 1.5;  // bent
    std::vector<double> targets(69, 0.0);
    targets[hinge] = -1.0;  // past straight, as a policy asks for its fastest extension
    double fastest = 0;
    for (int s = 0; s < 6; ++s) {
      pd.Step(targets.data(), d);
      fastest = std::max(fastest, -d->qvel[qvel]);
    }
    mj_deleteData(d);
    mj_deleteModel(m);
    return fastest;
  };
  const double servo = fastest_extension(PdMode::kPositionImplicitDamping);
  const double stable = fastest_extension(PdMode::kStablePd);
  EXPECT_LT(servo, 1.25 * kLimit / kd) << "stable PD: " << stable << " rad/s";
  EXPECT_GT(stable, 3 * kLimit / kd) << "position servo: " << servo << " rad/s";
}

}  // namespace
}  // namespace modskill
