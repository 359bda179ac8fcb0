// The servo settings' allowed values, which the server's flags and a policy file's physics
// record share: the PD mode names and the gain scale's range.
#include <cmath>
#include <limits>

#include <gmock/gmock.h>

#include "common/policy/physics_settings.h"
#include "common/servo_settings.h"
#include "server/core/sim/physics_options.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

TEST(ServoSettingsTest, GainScaleRangeIsOpenAtZeroAndClosedAtOneHundred) {
  for (double good : {1e-6, 0.6, 1.0, 100.0}) EXPECT_TRUE(ValidatePdGainScale(good, "--pd_gain_scale").ok()) << good;
  for (double bad : {0.0, -1.0, 100.000001, std::numeric_limits<double>::quiet_NaN(),
                     std::numeric_limits<double>::infinity()}) {
    const absl::Status status = ValidatePdGainScale(bad, "--pd_gain_scale");
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << bad;
    EXPECT_THAT(status.message(), HasSubstr("--pd_gain_scale: ")) << bad;
  }
}

TEST(ServoSettingsTest, TheServerAndThePolicyRecordTakeTheSameModeNames) {
  for (PdMode mode : {PdMode::kPositionImplicitDamping, PdMode::kStablePd}) {
    const absl::string_view name = PdModeName(mode);
    EXPECT_TRUE(IsPdModeName(name)) << name;
    ASSERT_TRUE(ParsePdMode(name).ok()) << name;
    EXPECT_EQ(*ParsePdMode(name), mode);
    PhysicsSettings physics;
    physics.physics_dt = 1.0 / 120;
    physics.pd_mode = std::string(name);
    EXPECT_TRUE(PhysicsSettings::FromJson(physics.ToJson(), "policy").ok()) << name;
  }
  EXPECT_FALSE(IsPdModeName("springs"));
  EXPECT_THAT(std::string(ParsePdMode("springs").status().message()), HasSubstr(kPdModeChoices));
}

TEST(ServoSettingsTest, TheServerAndThePolicyRecordRefuseTheSameGainScales) {
  for (double scale : {0.5, 100.0, 0.0, 100.5, -2.0}) {
    PhysicsSettings physics;
    physics.physics_dt = 1.0 / 120;
    physics.pd_gain_scale = scale;
    EXPECT_EQ(PhysicsSettings::FromJson(physics.ToJson(), "policy").ok(), ValidatePdGainScale(scale, "x").ok())
        << scale;
  }
}

}  // namespace
}  // namespace modskill
