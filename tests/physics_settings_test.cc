// The physics a policy records (rate and servos): its JSON, its validation, the wording of a
// difference, and a policy file that carries it or, from before the field, does not.
#include <string>

#include <gmock/gmock.h>

#include "common/policy/physics_settings.h"
#include "common/policy/policy_spec.h"
#include "server/core/env/env_spec.h"
#include "server/core/env/policy_fit.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

PhysicsSettings Default() {
  PhysicsSettings physics;
  physics.physics_dt = 1.0 / 120;
  return physics;
}

TEST(PhysicsSettingsTest, JsonRoundTripsAndBadFieldsAreNamed) {
  PhysicsSettings physics = Default();
  physics.pd_mode = "stable_pd";
  physics.pd_gain_scale = 0.6;
  physics.damp_to_reference_rate = true;
  auto read = PhysicsSettings::FromJson(physics.ToJson(), "policy");
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_DOUBLE_EQ(read->physics_dt, physics.physics_dt);
  EXPECT_EQ(read->pd_mode, "stable_pd");
  EXPECT_DOUBLE_EQ(read->pd_gain_scale, 0.6);
  EXPECT_TRUE(read->damp_to_reference_rate);
  EXPECT_EQ(PhysicsDifference(physics, *read, "its"), "");

  const std::pair<const char*, const char*> bad[] = {
      {R"({"physics_dt": 0, "pd_mode": "stable_pd", "pd_gain_scale": 1, "damp_to_reference_rate": false})",
       "policy: physics.physics_dt: 0 is not in (0, 1] s"},
      {R"({"physics_dt": 0.01, "pd_mode": "stable_pd", "pd_gain_scale": 1000, "damp_to_reference_rate": false})",
       "policy: physics.pd_gain_scale: 1000 must be finite, in (0, 100]"},
      {R"({"physics_dt": 0.01, "pd_mode": "springs", "pd_gain_scale": 1, "damp_to_reference_rate": false})",
       "policy: physics.pd_mode: \"springs\" is not position_implicit or stable_pd"},
      {R"({"physics_dt": 0.01, "pd_mode": "stable_pd", "pd_gain_scale": 1, "damp_to_reference_rate": 1})",
       "policy: physics.damp_to_reference_rate: missing or not true/false"},
      {R"({"pd_mode": "stable_pd", "pd_gain_scale": 1, "damp_to_reference_rate": false})",
       "policy: physics.physics_dt: missing or not a number"},
      {R"([1, 2])", "policy: physics: not a JSON object"},
  };
  for (const auto& [json, message] : bad) {
    auto refused = PhysicsSettings::FromJson(json, "policy");
    ASSERT_FALSE(refused.ok()) << json;
    EXPECT_EQ(refused.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(refused.status().message(), message);
  }
}

// Each setting is named with the server flag that sets it; nothing is compared against a side
// that does not record its physics.
TEST(PhysicsSettingsTest, TheFirstDifferenceIsWordedWithItsFlag) {
  const PhysicsSettings trained = Default();
  PhysicsSettings other = trained;
  other.physics_dt = 1.0 / 60;
  EXPECT_EQ(PhysicsDifference(trained, other, "this server's"),
            "physics_dt 0.00833333 s (120 Hz) against this server's 0.0166667 s (60 Hz); the server's --substeps sets it");
  other = trained;
  other.pd_mode = "stable_pd";
  EXPECT_THAT(PhysicsDifference(trained, other, "its"), HasSubstr("pd_mode position_implicit against its stable_pd"));
  other = trained;
  other.pd_gain_scale = 2;
  EXPECT_THAT(PhysicsDifference(trained, other, "its"), HasSubstr("pd_gain_scale 1 against its 2; the server's --pd_gain_scale"));
  other = trained;
  other.damp_to_reference_rate = true;
  EXPECT_THAT(PhysicsDifference(trained, other, "its"), HasSubstr("damp_to_reference_rate off against its on"));
  EXPECT_EQ(PhysicsDifference(PhysicsSettings(), other, "its"), "");
  EXPECT_EQ(PhysicsDifference(other, PhysicsSettings(), "its"), "");
}

// A policy file records the env's physics; one from before the field records none and fits any
// server; one with damaged physics is refused naming the field.
TEST(PhysicsSettingsTest, PolicyFilesCarryThePhysicsTheyWereTrainedWith) {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  ASSERT_TRUE(catalog.ok());
  PhysicsOptions options;
  options.substeps = 2;
  options.pd_gain_scale = 1.5;
  auto humanoid = HumanoidModel::Create(DefaultSpec(), options);
  ASSERT_TRUE(humanoid.ok());
  const EnvSpec env = MakeEnvSpec(**humanoid, *catalog->Get("5part"));
  EXPECT_NEAR(env.physics.physics_dt, 1.0 / 60, 1e-12);
  EXPECT_EQ(env.physics.pd_mode, "position_implicit");
  const PolicySpec trained = PolicySpecForEnv(env);
  auto read = PolicySpec::FromJson(trained.ToJson());
  ASSERT_TRUE(read.ok()) << read.status();
  EXPECT_NEAR(read->physics.physics_dt, 1.0 / 60, 1e-12);
  EXPECT_DOUBLE_EQ(read->physics.pd_gain_scale, 1.5);
  EXPECT_TRUE(CheckPolicyFitsEnv(*read, env).ok());

  auto default_humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  ASSERT_TRUE(default_humanoid.ok());
  const EnvSpec default_env = MakeEnvSpec(**default_humanoid, *catalog->Get("5part"));
  const absl::Status refused = CheckPolicyFitsEnv(*read, default_env);
  EXPECT_EQ(refused.code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(refused.message()), HasSubstr("checkpoint: trained with physics_dt 0.0166667 s (60 Hz) "
                                                        "against this server's 0.00833333 s (120 Hz)"));

  PolicySpec old = *read;
  old.physics = PhysicsSettings();
  auto old_read = PolicySpec::FromJson(old.ToJson());
  ASSERT_TRUE(old_read.ok()) << old_read.status();
  EXPECT_FALSE(old_read->physics.recorded());
  EXPECT_TRUE(CheckPolicyFitsEnv(*old_read, default_env).ok());

  std::string damaged = trained.ToJson();
  damaged.replace(damaged.find("position_implicit"), 17, "springs");
  auto damaged_read = PolicySpec::FromJson(damaged);
  ASSERT_FALSE(damaged_read.ok());
  EXPECT_THAT(std::string(damaged_read.status().message()), HasSubstr("env_spec.json: physics.pd_mode"));
}

}  // namespace
}  // namespace modskill
