// IndicesOfNames: the lookup behind reward_parts, --train_parts and splice --parts.
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/name_lookup.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

const std::vector<std::string> kParts = {"L_Leg", "R_Leg", "Torso", "L_Arm", "R_Arm"};

TEST(NameLookupTest, IndicesFollowTheNamesOrder) {
  auto indices = IndicesOfNames({"R_Arm", "L_Leg"}, kParts, "parts", "a part");
  ASSERT_TRUE(indices.ok()) << indices.status();
  EXPECT_EQ(*indices, (std::vector<int>{4, 0}));
  indices = IndicesOfNames({}, kParts, "parts", "a part");
  ASSERT_TRUE(indices.ok());
  EXPECT_TRUE(indices->empty());
}

TEST(NameLookupTest, UnknownAndRepeatedNamesAreRefusedByEntry) {
  auto unknown = IndicesOfNames({"Torso", "Tail"}, kParts, "reward_parts", "a part of layout '5part'");
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(unknown.status().message(),
            "reward_parts[1]: 'Tail' is not a part of layout '5part' (L_Leg, R_Leg, Torso, L_Arm, R_Arm)");
  auto twice = IndicesOfNames({"Torso", "L_Arm", "Torso"}, kParts, "--train_parts", "a part");
  EXPECT_EQ(twice.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(twice.status().message(), "--train_parts[2]: 'Torso' is given twice");
  // A client's name is shown bounded, whatever its size.
  auto huge = IndicesOfNames({std::string(100000, 'x')}, kParts, "reward_parts", "a part");
  EXPECT_LT(huge.status().message().size(), 300u);
  EXPECT_THAT(std::string(huge.status().message()), HasSubstr("(100000 bytes)"));
}

}  // namespace
}  // namespace modskill
