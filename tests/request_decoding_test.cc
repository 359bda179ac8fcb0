// What the server makes of a client's session config and a checkpoint's env_spec.json, without
// a server: ParseSessionConfig (server/service/session_config_validation.h) and
// PolicySpec::FromJson (policy_spec.h), the code fuzz/simulate_request_fuzzer and
// fuzz/policy_spec_fuzzer run. The seed inputs of both fuzzers are checked here too.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "common/policy/family_elites.h"
#include "common/policy/policy_spec.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"
#include "server/service/session_config_validation.h"

namespace modskill {
namespace {

constexpr int kMaxEnvs = 4096;
constexpr int kMaxLibraryClips = 10000;

const PartLayoutCatalog& Layouts() {
  static const PartLayoutCatalog* layouts = [] {
    auto skeleton = HumanoidSpec::LoadDefault();
    EXPECT_TRUE(skeleton.ok());
    auto catalog = PartLayoutCatalog::LoadDefault(*skeleton);
    EXPECT_TRUE(catalog.ok());
    return new PartLayoutCatalog(*std::move(catalog));
  }();
  return *layouts;
}

std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

absl::StatusCode CodeOf(const v1::SessionConfig& config) {
  return ParseSessionConfig(config, kMaxEnvs, kMaxLibraryClips, Layouts()).status().code();
}

TEST(SessionConfigTest, DefaultsFillTheUnsetFields) {
  v1::SessionConfig config;
  config.set_num_envs(3);
  auto settings = ParseSessionConfig(config, kMaxEnvs, kMaxLibraryClips, Layouts());
  ASSERT_TRUE(settings.ok()) << settings.status();
  EXPECT_EQ(settings->num_envs, 3);
  EXPECT_EQ(settings->layout.name, Layouts().default_name());
  EXPECT_EQ(settings->env.termination, TerminationMode::kTraining);
  EXPECT_DOUBLE_EQ(settings->env.termination_distance, 0.25);
  EXPECT_EQ(settings->env.action.mode, ActionMode::kAbsolute);
  EXPECT_EQ(settings->amp_frames, kAmpHistory);

  config.set_termination(v1::EVALUATION);
  config.set_amp_obs(v1::OMIT);
  config.set_action_mode(v1::RESIDUAL);
  settings = ParseSessionConfig(config, kMaxEnvs, kMaxLibraryClips, Layouts());
  ASSERT_TRUE(settings.ok()) << settings.status();
  EXPECT_DOUBLE_EQ(settings->env.termination_distance, 0.5);
  EXPECT_EQ(settings->env.action.mode, ActionMode::kResidual);
  EXPECT_EQ(settings->amp_frames, 0);
}

TEST(SessionConfigTest, EveryBadFieldHasItsCode) {
  v1::SessionConfig good;
  good.set_num_envs(1);
  ASSERT_EQ(CodeOf(good), absl::StatusCode::kOk);
  auto with = [&](auto change) {
    v1::SessionConfig config = good;
    change(config);
    return CodeOf(config);
  };
  EXPECT_EQ(with([](auto& c) { c.set_num_envs(0); }), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_num_envs(kMaxEnvs + 1); }), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(with([](auto& c) { c.set_max_episode_steps(-1); }), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_part_layout("7part"); }), absl::StatusCode::kNotFound);
  EXPECT_EQ(with([](auto& c) { c.set_termination(static_cast<v1::TerminationMode>(9)); }),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_termination_distance(std::nanf("")); }), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_termination_distance(-1); }), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_residual_scale(0.5f); }), absl::StatusCode::kInvalidArgument);  // not RESIDUAL
  EXPECT_EQ(with([](auto& c) { c.set_action_mode(static_cast<v1::ActionMode>(-4)); }),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_termination_bodies(static_cast<v1::TerminationBodies>(3)); }),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(with([](auto& c) { c.set_amp_obs(static_cast<v1::AmpObs>(4)); }), absl::StatusCode::kInvalidArgument);
}

// reward_parts resolve to their parts' bodies; an unknown or repeated part, or a goal task, is
// refused by name.
TEST(SessionConfigTest, RewardPartsResolveToTheirBodies) {
  v1::SessionConfig config;
  config.set_num_envs(1);
  auto settings = ParseSessionConfig(config, kMaxEnvs, kMaxLibraryClips, Layouts());
  ASSERT_TRUE(settings.ok()) << settings.status();
  EXPECT_TRUE(settings->env.reward.bodies.empty());  // every body

  config.add_reward_parts("R_Arm");
  config.add_reward_parts("L_Arm");
  settings = ParseSessionConfig(config, kMaxEnvs, kMaxLibraryClips, Layouts());
  ASSERT_TRUE(settings.ok()) << settings.status();
  std::vector<int> expected;
  for (const BodyPart& part : settings->layout.parts) {
    if (part.name == "R_Arm" || part.name == "L_Arm") expected.insert(expected.end(), part.bodies.begin(), part.bodies.end());
  }
  std::sort(expected.begin(), expected.end());
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(settings->env.reward.bodies, expected);

  const auto refusal = [&](auto change) {
    v1::SessionConfig bad = config;
    change(bad);
    return ParseSessionConfig(bad, kMaxEnvs, kMaxLibraryClips, Layouts()).status();
  };
  absl::Status status = refusal([](auto& c) { c.set_reward_parts(1, "Tail"); });
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), ::testing::HasSubstr("reward_parts[1]: 'Tail'"));
  status = refusal([](auto& c) { c.set_reward_parts(1, "R_Arm"); });
  EXPECT_THAT(std::string(status.message()), ::testing::HasSubstr("reward_parts[1]: 'R_Arm' is given twice"));
  status = refusal([](auto& c) { c.set_task("steer"); });
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), ::testing::HasSubstr("reward_parts: task steer"));

  EXPECT_FALSE(settings->env.reward.relative_to_root);
  config.set_reward_relative_to_root(true);
  settings = ParseSessionConfig(config, kMaxEnvs, kMaxLibraryClips, Layouts());
  ASSERT_TRUE(settings.ok()) << settings.status();
  EXPECT_TRUE(settings->env.reward.relative_to_root);
  status = refusal([](auto& c) {
    c.clear_reward_parts();
    c.set_reward_relative_to_root(true);
    c.set_task("reach");
  });
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(status.message()), ::testing::HasSubstr("reward_relative_to_root: task reach"));
}

TEST(SessionConfigTest, SeedRequestsOfTheFuzzerDecode) {
  const std::filesystem::path dir = std::filesystem::path(MODSKILL_REPO_DIR) / "fuzz/corpus/simulate_request";
  int configs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    v1::SimulateRequest request;
    ASSERT_TRUE(request.ParseFromString(ReadFile(entry.path()))) << entry.path();
    if (!request.has_config()) continue;
    EXPECT_TRUE(ParseSessionConfig(request.config(), kMaxEnvs, kMaxLibraryClips, Layouts()).ok()) << entry.path();
    ++configs;
  }
  EXPECT_GE(configs, 3);
}

TEST(PolicySpecTest, ShippedSpecsParseAndRoundTrip) {
  const std::filesystem::path dir = std::filesystem::path(MODSKILL_REPO_DIR) / "fuzz/corpus/policy_spec";
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    auto spec = PolicySpec::FromJson(ReadFile(entry.path()));
    ASSERT_TRUE(spec.ok()) << entry.path() << ": " << spec.status();
    EXPECT_EQ(spec->action_size, static_cast<int>(spec->joint_names.size()));
    auto again = PolicySpec::FromJson(spec->ToJson());
    ASSERT_TRUE(again.ok()) << again.status();
    EXPECT_EQ(again->ToJson(), spec->ToJson());
  }
}

TEST(PolicySpecTest, BadSpecsAreInvalidArgument) {
  for (const char* json : {"", "[]", "{}", R"({"part_layout": 5})",
                           R"({"part_layout": "5part", "obs_size": 1099511627776, "action_size": 1,
                               "joint_names": [], "control_dt": 0.03})",
                           R"({"part_layout": "5part", "obs_size": 1, "action_size": 1, "joint_names": [],
                               "control_dt": 0.03, "action_mode": "sideways"})"}) {
    EXPECT_EQ(PolicySpec::FromJson(json).status().code(), absl::StatusCode::kInvalidArgument) << json;
  }
}

// Task and controller_input: recorded and read back; files from before them read as a tracker
// with part_obs controllers; bad values are INVALID_ARGUMENT naming the field.
TEST(PolicySpecTest, TaskAndControllerInputRoundTripWithDefaultsForOldFiles) {
  const std::string old_json =
      R"({"part_layout": "5part", "obs_size": 3, "action_size": 1, "joint_names": ["a"], "control_dt": 0.03})";
  auto old_spec = PolicySpec::FromJson(old_json);
  ASSERT_TRUE(old_spec.ok()) << old_spec.status();
  EXPECT_EQ(old_spec->task, "tracking");
  EXPECT_EQ(old_spec->controller_input, "part_obs");
  PolicySpec task_policy = *old_spec;
  task_policy.task = "vr_tracking";
  task_policy.controller_input = "proprioception";
  auto again = PolicySpec::FromJson(task_policy.ToJson());
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->task, "vr_tracking");
  EXPECT_EQ(again->controller_input, "proprioception");
  const std::string head = old_json.substr(0, old_json.size() - 1);
  for (const auto& [field, value] : std::vector<std::pair<std::string, std::string>>{
           {"task", R"("")"}, {"task", R"("Steer!")"}, {"task", R"("a_name_far_longer_than_any_task_name")"},
           {"task", "7"}, {"controller_input", R"("reference")"}, {"controller_input", "null"}}) {
    const std::string json = absl::StrCat(head, R"(, ")", field, R"(": )", value, "}");
    auto bad = PolicySpec::FromJson(json);
    EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument) << json;
    EXPECT_THAT(std::string(bad.status().message()), ::testing::HasSubstr(field)) << json;
  }
}

// reference_frames: recorded and read back; files from before it observed one frame; a count
// outside [1, 8], a non-integer or a task policy with more than one is INVALID_ARGUMENT naming it.
TEST(PolicySpecTest, ReferenceFramesRoundTripWithOneForOldFiles) {
  const std::string head =
      R"({"part_layout": "5part", "obs_size": 3, "action_size": 1, "joint_names": ["a"], "control_dt": 0.03)";
  auto old_spec = PolicySpec::FromJson(head + "}");
  ASSERT_TRUE(old_spec.ok()) << old_spec.status();
  EXPECT_EQ(old_spec->reference_frames, 1);
  PolicySpec lookahead = *old_spec;
  lookahead.reference_frames = 3;
  auto again = PolicySpec::FromJson(lookahead.ToJson());
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_EQ(again->reference_frames, 3);
  for (const char* tail : {R"(, "reference_frames": 0)", R"(, "reference_frames": 9)",
                           R"(, "reference_frames": 2.5)", R"(, "reference_frames": "3")",
                           R"(, "reference_frames": 2, "task": "steer")"}) {
    auto bad = PolicySpec::FromJson(head + tail + "}");
    EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument) << tail;
    EXPECT_THAT(std::string(bad.status().message()), ::testing::HasSubstr("reference_frames")) << tail;
  }
}

// A family's clip, frames and ranges: recorded and read back; bad ones are INVALID_ARGUMENT naming
// the field; the elite file parses only as finite elites of the family's size.
TEST(PolicySpecTest, FamilyFieldsRoundTripAndBadOnesAreNamed) {
  const std::string head =
      R"({"part_layout": "5part", "obs_size": 3, "action_size": 1, "joint_names": ["a"], "control_dt": 0.03)";
  auto plain = PolicySpec::FromJson(head + "}");
  ASSERT_TRUE(plain.ok());
  EXPECT_FALSE(plain->is_family());
  PolicySpec family = *plain;
  family.family_clip = "deepmimic_jump";
  family.family_frames = 53;
  family.family = {{"gravity", 4, 14}, {"body_mass_scale", 0.8, 1.2}};
  auto again = PolicySpec::FromJson(family.ToJson());
  ASSERT_TRUE(again.ok()) << again.status();
  ASSERT_TRUE(again->is_family());
  EXPECT_EQ(again->family_clip, "deepmimic_jump");
  EXPECT_EQ(again->family_frames, 53);
  ASSERT_EQ(again->family.size(), 2u);
  EXPECT_EQ(again->family[1].name, "body_mass_scale");
  EXPECT_EQ(again->family[1].lo, 0.8);
  const std::string clip = R"(, "family_clip": "deepmimic_jump", "family_frames": 53)";
  for (const auto& [field, tail] : std::vector<std::pair<std::string, std::string>>{
           {"family", R"(, "family": [])"},
           {"family[0]", R"(, "family": [{"name": "gravity", "lo": 14, "hi": 4}])" + clip},
           {"family[0]", R"(, "family": [{"name": "warp_speed", "lo": 1, "hi": 2}])" + clip},
           {"family[1]", R"(, "family": [{"name": "gravity", "lo": 4, "hi": 14}, {"name": "gravity", "lo": 4, "hi": 5}])" + clip},
           {"family_clip", R"(, "family": [{"name": "gravity", "lo": 4, "hi": 14}], "family_clip": "", "family_frames": 53)"},
           {"family_frames", R"(, "family": [{"name": "gravity", "lo": 4, "hi": 14}], "family_clip": "x", "family_frames": 1)"}}) {
    auto bad = PolicySpec::FromJson(head + tail + "}");
    EXPECT_EQ(bad.status().code(), absl::StatusCode::kInvalidArgument) << tail;
    EXPECT_THAT(std::string(bad.status().message()), ::testing::HasSubstr(field)) << tail;
  }

  auto elites = FamilyElitesFromJson(FamilyElitesToJson({{{5.0, 1.0}, 0.4}, {{13.5, 0.9}, 0.2}}), 2);
  ASSERT_TRUE(elites.ok()) << elites.status();
  ASSERT_EQ(elites->size(), 2u);
  EXPECT_EQ((*elites)[1].params, (std::vector<double>{13.5, 0.9}));
  EXPECT_EQ((*elites)[1].fitness, 0.2);
  for (const char* bad : {"{}", R"([{"params": [1], "fitness": 0.5}])", R"([{"params": [1, 2]}])",
                          R"([{"params": [1, 2], "fitness": "high"}])", "[1, 2]"}) {
    EXPECT_EQ(FamilyElitesFromJson(bad, 2).status().code(), absl::StatusCode::kInvalidArgument) << bad;
  }
}

}  // namespace
}  // namespace modskill
