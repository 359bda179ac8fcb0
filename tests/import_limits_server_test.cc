// Issue 10 through the server: the importer reproducers uploaded with AddMotions answer
// INVALID_ARGUMENT naming the field (no UNKNOWN after gigabytes of allocation), and a clip named
// to climb out of --save_generated never gets in, so nothing is written outside it.
#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "tests/npz_test_writer.h"
#include "tests/process_memory.h"
#include "tests/server_fixture.h"
#include "tests/test_files.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

// What a refused upload may make the (in-process) server allocate at its peak.
constexpr int64_t kMaxRejectionGrowth = int64_t{128} << 20;

class ImportLimitsServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = std::filesystem::path(TestTempPath("import_limits_server_test", "root"));
    std::filesystem::remove_all(root_);
    save_dir_ = root_ / "a" / "b" / "generated";
    std::filesystem::create_directories(save_dir_);
    ServerOptions options;
    options.service.generated_clip_dir = save_dir_.string();
    server_ = StartTestServer(options);
    ASSERT_NE(server_, nullptr);
    client_ = ConnectTo(*server_);
    ASSERT_NE(client_, nullptr);
  }
  void TearDown() override { server_->Shutdown(absl::Seconds(1)); }

  // Uploads one file and expects INVALID_ARGUMENT mentioning every fragment.
  void ExpectRejected(const std::string& file_name, const std::string& data, const std::string& name,
                      const std::vector<std::string>& fragments) {
    v1::AddMotionsRequest request;
    v1::MotionUpload* upload = request.add_uploads();
    upload->set_file_name(file_name);
    upload->set_data(data);
    upload->set_name(name);
    absl::StatusOr<v1::AddMotionsResponse> added;
    // Before the fix these took the server to 2.2-2.5 GB; refused, they cost a copy of the upload.
    const int64_t growth = testing::PeakGrowthBytes([&] { added = client_->AddMotions(request); });
    EXPECT_LT(growth, kMaxRejectionGrowth) << file_name << ": peak resident memory rose by " << (growth >> 20) << " MiB";
    ASSERT_FALSE(added.ok()) << file_name;
    EXPECT_EQ(added.status().code(), absl::StatusCode::kInvalidArgument) << added.status();
    for (const std::string& fragment : fragments) EXPECT_THAT(std::string(added.status().message()), HasSubstr(fragment));
  }

  std::filesystem::path root_, save_dir_;
  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<SimulationClient> client_;
};

TEST_F(ImportLimitsServerTest, TinyFrameRateBvh) {
  const std::string bvh =
      "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation "
      "Xrotation\n  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\nMOTION\nFrames: 2\nFrame Time: 100000\n"
      "0 90 0 0 0 0\n0 90 1 0 0 0\n";
  ExpectRejected("slow.bvh", bvh, "", {"uploads[0]", "Frame Time", "max_clip_seconds"});
}

TEST_F(ImportLimitsServerTest, CompressedZeroFrameBomb) {
  testing::NpzWriter writer;
  writer.AddF32("poses", {200000, 72}, std::vector<float>(size_t{200000} * 72, 0.f));
  writer.AddF32("trans", {200000, 3}, std::vector<float>(size_t{200000} * 3, 0.f));
  writer.AddF64("mocap_framerate", {}, {120.0});
  const std::string npz = writer.Serialize(/*compress=*/true);
  ASSERT_LT(npz.size(), size_t{1} << 20);
  ExpectRejected("bomb.npz", npz, "", {"bomb.npz", "max_clip_frames"});
}

TEST_F(ImportLimitsServerTest, TraversalNameNeverReachesSaveGenerated) {
  auto walk = ReadFileToString(std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_walk.txt",
                               1 << 20);
  ASSERT_TRUE(walk.ok());
  for (const std::string& name : std::vector<std::string>{"../../x/evil", "..", "a/b", ".hidden", std::string(4096, 'n')}) {
    ExpectRejected("humanoid3d_walk.txt", *walk, name, {"uploads[0]", "name"});
  }
  // Nothing was written anywhere under the test's root but the save directory itself.
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root_)) {
    EXPECT_TRUE(entry.is_directory()) << entry.path();
  }
  auto listed = client_->ListMotions();
  ASSERT_TRUE(listed.ok());
  EXPECT_EQ(listed->motions_size(), DefaultMotions()->size());
}

}  // namespace
}  // namespace modskill
