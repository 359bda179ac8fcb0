// MuJoCo's warnings reach the log (once per message every few seconds, with a count of repeats)
// instead of a MUJOCO_LOG.TXT in the working directory.
#include <unistd.h>

#include <filesystem>
#include <string>

#include <gmock/gmock.h>
#include <mujoco/mujoco.h>

#include "server/core/sim/humanoid_model.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

TEST(MujocoWarningsTest, GoToTheLogNotToAFileInTheWorkingDirectory) {
  const std::filesystem::path directory = std::filesystem::path(MODSKILL_TEST_TMP_DIR) / "mujoco_warnings";
  std::filesystem::remove_all(directory);
  std::filesystem::create_directories(directory);
  const std::filesystem::path previous = std::filesystem::current_path();
  std::filesystem::current_path(directory);
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());  // installs the route
  ASSERT_TRUE(humanoid.ok()) << humanoid.status();
  ::testing::internal::CaptureStderr();
  for (int i = 0; i < 100; ++i) mju_warning("Nan, Inf or huge value in QACC at DOF 7");
  const std::string logged = ::testing::internal::GetCapturedStderr();
  std::filesystem::current_path(previous);
  EXPECT_FALSE(std::filesystem::exists(directory / "MUJOCO_LOG.TXT"));
  EXPECT_THAT(logged, HasSubstr("MuJoCo warning: Nan, Inf or huge value in QACC at DOF 7"));
  // A hundred repeats in a burst: one line.
  EXPECT_EQ(logged.find("MuJoCo warning"), logged.rfind("MuJoCo warning")) << logged;
}

}  // namespace
}  // namespace modskill
