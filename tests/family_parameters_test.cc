// The family parameter catalog, `--param name=lo:hi` parsing and normalization
// (common/policy/family_parameters.h).
#include "common/policy/family_parameters.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace modskill {
namespace {

using ::testing::HasSubstr;

TEST(FamilyParametersTest, CatalogHasTheServersNames) {
  for (const char* name : {"gravity", "leg_scale", "arm_scale", "body_mass_scale", "jump_height", "target_height",
                           "obstacle_height", "obstacle_distance"}) {
    EXPECT_NE(FindFamilyParameter(name), nullptr) << name;
  }
  EXPECT_EQ(FamilyParameterCatalog().size(), 8u);
  EXPECT_DOUBLE_EQ(*FindFamilyParameter("gravity")->default_value, 9.81);
  EXPECT_STREQ(FindFamilyParameter("gravity")->unit, "m/s^2");
  EXPECT_FALSE(FindFamilyParameter("jump_height")->default_value.has_value());
  EXPECT_EQ(FindFamilyParameter("wind"), nullptr);
}

TEST(FamilyParametersTest, ParsesRangesAndConstraints) {
  absl::StatusOr<ParamRange> range = ParseParamRange("gravity=4:14");
  ASSERT_TRUE(range.ok()) << range.status();
  EXPECT_EQ(range->name, "gravity");
  EXPECT_DOUBLE_EQ(range->lo, 4);
  EXPECT_DOUBLE_EQ(range->hi, 14);
  absl::StatusOr<ParamRange> constraint = ParseParamRange("leg_scale=1.2");
  ASSERT_TRUE(constraint.ok()) << constraint.status();
  EXPECT_DOUBLE_EQ(constraint->lo, 1.2);
  EXPECT_DOUBLE_EQ(constraint->hi, 1.2);
  EXPECT_TRUE(ParseParamRange("jump_height=0.3:0.3").ok());  // zero width: a constraint
}

TEST(FamilyParametersTest, RefusesBadRangesNamingTheParameter) {
  const struct {
    const char* text;
    const char* message;
  } cases[] = {
      {"wind=1:2", "'wind' is not a family parameter"},
      {"gravity=14:4", "gravity: range 14:4 is inverted"},
      {"gravity=nan:4", "gravity: range nan:4 is not finite"},
      {"gravity=1:inf", "gravity: range 1:inf is not finite"},
      {"gravity=a:4", "gravity: 'a' is not a number"},
      {"gravity=1:2:3", "gravity: '1:2:3' is not lo:hi"},
      {"gravity", "is not name=lo:hi"},
      {"leg_scale=0:1", "leg_scale: lo 0 must be > 0"},
      {"obstacle_height=-1:1", "obstacle_height: lo -1 must be >= 0"},
  };
  for (const auto& c : cases) {
    absl::StatusOr<ParamRange> range = ParseParamRange(c.text);
    ASSERT_FALSE(range.ok()) << c.text;
    EXPECT_EQ(range.status().code(), absl::StatusCode::kInvalidArgument) << c.text;
    EXPECT_THAT(std::string(range.status().message()), HasSubstr(c.message)) << c.text;
  }
}

TEST(FamilyParametersTest, RefusesDuplicates) {
  absl::StatusOr<std::vector<ParamRange>> ranges =
      ParseParamRanges({"gravity=4:14", "leg_scale=0.8:1.2", "gravity=5:6"});
  ASSERT_FALSE(ranges.ok());
  EXPECT_EQ(ranges.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(ranges.status().message()), HasSubstr("gravity is given twice"));
  EXPECT_FALSE(ParamSpace::Create({{"gravity", 1, 2}, {"gravity", 1, 2}}).ok());
  EXPECT_FALSE(ParamSpace::Create({}).ok());
  ASSERT_TRUE(ParseParamRanges({"gravity=4:14", "leg_scale=0.8:1.2"}).ok());
}

TEST(FamilyParametersTest, NormalizesToTheUnitCube) {
  absl::StatusOr<ParamSpace> space = ParamSpace::Create({{"gravity", 4, 14}, {"leg_scale", 1.2, 1.2}, {"jump_height", 0, 2}});
  ASSERT_TRUE(space.ok()) << space.status();
  EXPECT_TRUE(space->is_constraint(1));
  EXPECT_FALSE(space->is_constraint(0));
  absl::StatusOr<std::vector<double>> u = space->Normalize({9, 1.2, 0.5});
  ASSERT_TRUE(u.ok()) << u.status();
  EXPECT_THAT(*u, ::testing::ElementsAre(0.5, 0.0, 0.25));  // the zero-width dimension maps to 0
  absl::StatusOr<std::vector<double>> a = space->Denormalize(*u);
  ASSERT_TRUE(a.ok());
  EXPECT_THAT(*a, ::testing::ElementsAre(9, 1.2, 0.5));
  absl::StatusOr<std::vector<double>> outside = space->Normalize({15, 1.2, 0.5});
  ASSERT_FALSE(outside.ok());
  EXPECT_THAT(std::string(outside.status().message()), HasSubstr("gravity: 15 is outside 4:14"));
  EXPECT_FALSE(space->Normalize({9, 1.2}).ok());
  EXPECT_FALSE(space->Denormalize({std::nan(""), 0, 0}).ok());
}

}  // namespace
}  // namespace modskill
