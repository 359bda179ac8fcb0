// The reach teacher (--task_teacher, reach_teacher.h): its text table, the nearest held pose's z
// per goal, the parts it supervises, its loss, the files it refuses, and a reach run that trains
// with it against an in-process server.
#include "learner/reach_teacher.h"

#include <filesystem>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/atomic_file.h"
#include "learner/task_evaluation.h"
#include "learner/trainer.h"
#include "tests/server_fixture.h"
#include "tests/trainer_test_config.h"

namespace modskill::learner {
namespace {

using ::testing::HasSubstr;

// Two parts of 2 dims; entry "low" holds the hand at (0.3, 0, 0), "high" at (0.3, 0, 0.6).
const char kTable[] =
    "# a comment\n"
    "parts Arm Leg\n"
    "embed_dim 2\n"
    "entry low 0.3 0 0  2 0  0 1\n"
    "entry high 0.3 0 0.6  0 3  1 0\n";

absl::Status ParseError(const std::string& text) { return ReachTeacher::Parse(text, "t.txt").status(); }

TEST(ReachTeacherTest, GivesTheUnitZOfTheHeldPoseNearestEachGoal) {
  auto teacher = ReachTeacher::Parse(kTable, "t.txt");
  ASSERT_TRUE(teacher.ok()) << teacher.status();
  EXPECT_EQ(teacher->size(), 2);
  EXPECT_EQ(teacher->parts(), (std::vector<std::string>{"Arm", "Leg"}));
  const torch::Tensor goals = torch::tensor({0.3f, 0.f, 0.1f, 0.5f, 0.2f, 0.5f, -1.f, 0.f, 2.f}).view({3, 3});
  const torch::Tensor z = teacher->NearestZ(goals);
  ASSERT_EQ(z.sizes(), (std::vector<int64_t>{3, 2, 2}));
  const torch::Tensor low = torch::tensor({1.f, 0.f, 0.f, 1.f}).view({2, 2});
  const torch::Tensor high = torch::tensor({0.f, 1.f, 1.f, 0.f}).view({2, 2});
  EXPECT_TRUE(torch::equal(z[0], low)) << "normalized to the sphere, nearest to a goal 0.1 m above 'low'";
  EXPECT_TRUE(torch::equal(z[1], high));
  EXPECT_TRUE(torch::equal(z[2], high)) << "an unreachable goal takes the nearest pose";
}

// A reach layout's parts (names only) and its goal, a point.
NetworkLayout LayoutOf(const std::vector<std::string>& parts, int64_t goal_size = 3) {
  NetworkLayout layout;
  for (const std::string& name : parts) layout.parts.push_back(PartSlices{name});
  layout.goal_size = goal_size;
  return layout;
}

TEST(ReachTeacherTest, SupervisesTheTaskPartsOfTheSameSkillsOnly) {
  auto teacher = ReachTeacher::Parse(kTable, "t.txt");
  ASSERT_TRUE(teacher.ok());
  auto all = teacher->PartMask(LayoutOf({"Arm", "Leg"}), 2, {});
  ASSERT_TRUE(all.ok()) << all.status();
  EXPECT_TRUE(torch::equal(*all, torch::tensor({1.f, 1.f})));
  auto arm = teacher->PartMask(LayoutOf({"Arm", "Leg"}), 2, {"Arm"});
  ASSERT_TRUE(arm.ok());
  EXPECT_TRUE(torch::equal(*arm, torch::tensor({1.f, 0.f})));
  for (const auto& [parts, embed] : {std::pair<std::vector<std::string>, int64_t>{{"Arm", "Leg"}, 32},
                                     std::pair<std::vector<std::string>, int64_t>{{"Leg", "Arm"}, 2}}) {
    auto other = teacher->PartMask(LayoutOf(parts), embed, {});
    EXPECT_EQ(other.status().code(), absl::StatusCode::kFailedPrecondition);
    EXPECT_THAT(other.status().message(), HasSubstr("--task_teacher: its z are for parts (Arm,Leg) of 2 dims"));
  }
  auto not_a_point = teacher->PartMask(LayoutOf({"Arm", "Leg"}, 934), 2, {});
  EXPECT_EQ(not_a_point.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(not_a_point.status().message(), HasSubstr("--task_teacher: the task's goal has 934 features"));
}

TEST(ReachTeacherTest, LossIsTheSquaredDistanceOverTheSupervisedParts) {
  const torch::Tensor z = torch::tensor({1.f, 0.f, 0.f, 1.f}).view({1, 2, 2});
  const torch::Tensor teacher = torch::tensor({0.f, 1.f, 0.f, 1.f}).view({1, 2, 2});
  EXPECT_DOUBLE_EQ(TeacherLoss(z, teacher, torch::tensor({1.f, 1.f})).item<double>(), 1.0);  // (2 + 0) / 2 parts
  EXPECT_DOUBLE_EQ(TeacherLoss(z, teacher, torch::tensor({0.f, 1.f})).item<double>(), 0.0);
  EXPECT_DOUBLE_EQ(TeacherLoss(z, teacher, torch::tensor({1.f, 0.f})).item<double>(), 2.0);
}

TEST(ReachTeacherTest, WeightFallsLinearlyToZeroOverTheFadeSteps) {
  EXPECT_EQ(TeacherWeightAt(2.0, 0, 1000000), 2.0) << "0: held";
  EXPECT_EQ(TeacherWeightAt(2.0, 100, 0), 2.0);
  EXPECT_DOUBLE_EQ(TeacherWeightAt(2.0, 100, 25), 1.5);
  EXPECT_EQ(TeacherWeightAt(2.0, 100, 100), 0.0);
  EXPECT_EQ(TeacherWeightAt(2.0, 100, 250), 0.0);
}

TEST(ReachTeacherTest, MalformedTablesAreClearErrorsNamingTheLine) {
  const std::pair<std::string, std::string> cases[] = {
      {"entry a 0 0 0 1 0\n", "t.txt:1: an entry before the 'parts' and 'embed_dim' lines"},
      {"parts A\nembed_dim 2\nentry a 0 0 0 1\n", "t.txt:3: entry 'a' has 4 numbers, expected 5"},
      {"parts A\nembed_dim 2\nentry a 0 nan 0 1 0\n", "t.txt:3: entry 'a' number 2: 'nan' is not a finite number"},
      {"parts A\nembed_dim 2\nentry a 0 x 0 1 0\n", "number 2: 'x' is not a finite number"},
      {"parts A\nembed_dim 0\n", "t.txt:2: embed_dim must be one integer in [1, 4096]"},
      {"parts A\nparts B\n", "t.txt:2: a second 'parts' line"},
      {"parts\n", "t.txt:1: 'parts' names no part"},
      {"{\"json\": 1}\n", "t.txt:1: unknown line '{\"json\":'"},
      {"parts A\nembed_dim 2\n", "t.txt: no entries"},
      {"parts A\nembed_dim 2\nentry a 0 0 0 0 0\n", "t.txt: an entry has a zero z"},
  };
  for (const auto& [text, message] : cases) {
    const absl::Status status = ParseError(text);
    EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << text;
    EXPECT_THAT(status.message(), HasSubstr(message)) << text;
  }
}

TEST(ReachTeacherTest, AMissingFileNamesTheFlag) {
  auto missing = ReachTeacher::Load("/nonexistent/teacher.txt");
  EXPECT_FALSE(missing.ok());
  EXPECT_THAT(missing.status().message(), HasSubstr("--task_teacher: "));
}

std::string RunDir(const std::string& name) {
  const std::string dir = std::string(MODSKILL_TEST_TMP_DIR) + "/reach_teacher/" + name;
  std::filesystem::remove_all(dir);
  return dir;
}

// A teacher table for `parts` with 8 random held poses in front of the character.
std::string WriteTeacher(const std::string& path, const std::vector<std::string>& parts, int64_t embed_dim) {
  torch::manual_seed(5);
  std::string text = absl::StrCat("parts ", absl::StrJoin(parts, " "), "\nembed_dim ", embed_dim, "\n");
  for (int k = 0; k < 8; ++k) {
    absl::StrAppend(&text, "entry pose", k, " ", 0.1 * k, " -0.3 ", 0.1 * (k % 4));
    const torch::Tensor z = torch::randn({static_cast<int64_t>(parts.size()) * embed_dim});
    for (int64_t i = 0; i < z.numel(); ++i) absl::StrAppend(&text, " ", z[i].item<float>());
    text += "\n";
  }
  EXPECT_TRUE(WriteFileAtomically(path, text).ok());
  return path;
}

// A reach head over a tracker's skills trains with the teacher: its weight falls to 0 over
// --task_teacher_steps, its loss is reported while it pulls, the exported policy evaluates with a
// row for the teacher itself; a teacher made for other skills is refused before training.
TEST(ReachTeacherTest, AReachRunTrainsWithTheTeacherAndEvaluatesIt) {
  auto server = StartTestServer();
  const std::string server_address = absl::StrCat("127.0.0.1:", server->port());
  auto skills = TrainWalkSkills({server_address}, RunDir("tracker"));
  ASSERT_TRUE(skills.ok()) << skills.status();

  const std::string dir = RunDir("reach");
  TrainerConfig config = SmallTestTrainerConfig({server_address}, dir);
  config.motions = {"deepmimic_walk"};
  config.task = "reach";
  config.skills = *skills;
  config.task_parts = {"R_Arm"};
  config.iterations = 3;
  config.report_every = 1;
  std::filesystem::create_directories(dir);
  config.task_teacher = WriteTeacher(dir + "/../teacher.txt", {"L_Leg", "R_Leg", "Torso", "L_Arm", "R_Arm"}, 32);
  config.task_teacher_weight = 2;
  config.task_teacher_steps = 1;  // gone after the first iteration's steps
  auto trainer = Trainer::Create(config);
  ASSERT_TRUE(trainer.ok()) << trainer.status();
  ASSERT_TRUE((*trainer)->Run().ok());
  const std::vector<IterationStats>& history = (*trainer)->history();
  ASSERT_EQ(history.size(), 3u);
  EXPECT_EQ(history[0].teacher_weight, 2.0) << "the first update comes before any step counts";
  EXPECT_EQ(history[1].teacher_weight, 0.0);
  EXPECT_GT(history[0].teacher_loss, 0.0);
  EXPECT_EQ(history[1].teacher_loss, 0.0) << "no pull at weight 0";

  auto client = ConnectTo(*server);
  auto imported = ImportTaskPolicy(dir + "/policy.pt", (*trainer)->spec());
  ASSERT_TRUE(imported.ok()) << imported.status();
  TaskEvaluationOptions options = SmallTaskEvaluation("reach", config, 20);
  auto teacher = ReachTeacher::Load(config.task_teacher);
  ASSERT_TRUE(teacher.ok());
  options.teacher = &*teacher;
  options.teacher_parts = torch::tensor({0.f, 0.f, 0.f, 0.f, 1.f});
  auto report = EvaluateTaskPolicy(*client, *imported, "reach policy", options);
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_EQ(report->rows.size(), 5u) << "the policy, random z, constant z, the prior and the teacher";
  EXPECT_THAT(report->rows.back().z_source, HasSubstr("teacher"));
  EXPECT_EQ(report->rows.back().episodes, 4);

  TrainerConfig other = config;
  other.run_dir = RunDir("reach_other_skills");
  other.task_teacher = WriteTeacher(dir + "/../teacher16.txt", {"L_Leg", "R_Leg", "Torso", "L_Arm", "R_Arm"}, 16);
  auto refused = Trainer::Create(other);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(refused.status().message(), HasSubstr("--task_teacher: its z are for parts"));
  server->Shutdown(absl::Seconds(1));
}

}  // namespace
}  // namespace modskill::learner
