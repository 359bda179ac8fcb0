// Per-test scratch files: ctest runs each test in its own process, possibly in parallel, so
// every test gets its own file names.
#ifndef MODSKILL_TESTS_TEST_FILES_H_
#define MODSKILL_TESTS_TEST_FILES_H_

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"

namespace modskill {

// MODSKILL_TEST_TMP_DIR/<subdirectory>/<suite>.<test>.<file_name>
inline std::string TestTempPath(const std::string& subdirectory, const std::string& file_name) {
  const std::filesystem::path directory = std::filesystem::path(MODSKILL_TEST_TMP_DIR) / subdirectory;
  std::filesystem::create_directories(directory);
  const ::testing::TestInfo* test = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string test_name =
      absl::StrReplaceAll(absl::StrCat(test->test_suite_name(), ".", test->name()), {{"/", "_"}});
  return (directory / absl::StrCat(test_name, ".", file_name)).string();
}

// MODSKILL_TEST_TMP_DIR/<subdirectory>/pid<N>: for files a suite shares between its tests
// (a tracker exported once, a server's checkpoint directory), which concurrent test processes
// must not overwrite under each other.
inline std::string ProcessTempDir(const std::string& subdirectory) {
  const std::filesystem::path directory =
      std::filesystem::path(MODSKILL_TEST_TMP_DIR) / subdirectory / absl::StrCat("pid", getpid());
  std::filesystem::create_directories(directory);
  return directory.string();
}

inline void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  file.close();
  ASSERT_FALSE(file.fail()) << path;
}

}  // namespace modskill

#endif  // MODSKILL_TESTS_TEST_FILES_H_
