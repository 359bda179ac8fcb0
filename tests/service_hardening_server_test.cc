// Issue 10 through the server, the service's side: a rollout reads checkpoint files only in the
// operator's --checkpoint_dir directories and answers the same for any path outside them; status
// messages never echo a client's string at length (the client's metadata limit would turn them
// into RESOURCE_EXHAUSTED and kill the channel's other calls); SampleReferenceAmp refuses, naming
// the field, what would not fit the message limit.
#include <sys/stat.h>

#include <filesystem>
#include <string>

#include <gmock/gmock.h>

#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "common/policy/policy_checkpoint.h"
#include "server/core/env/policy_fit.h"
#include "server/core/sim/humanoid_model.h"
#include "server/core/sim/part_layout.h"
#include "tests/process_memory.h"
#include "tests/server_fixture.h"
#include "tests/test_files.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

// Status messages as the client reports them: the server's capped message plus the RPC's name.
constexpr size_t kMaxClientMessage = 1200;

std::string WriteZeroPolicy(const std::string& path) {
  auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
  auto humanoid = HumanoidModel::Create(DefaultSpec(), PhysicsOptions());
  const EnvSpec spec = MakeEnvSpec(**humanoid, *catalog->Get("5part"));
  EXPECT_TRUE(SaveAffinePolicy(path, PolicySpecForEnv(spec), {}, {}).ok());
  return path;
}

class CheckpointDirTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = std::filesystem::path(TestTempPath("service_hardening", "root"));
    std::filesystem::remove_all(root_);
    allowed_ = root_ / "checkpoints";
    std::filesystem::create_directories(allowed_);
    std::filesystem::create_directories(root_ / "private");
    policy_ = WriteZeroPolicy((allowed_ / "zero.pt").string());
    outside_policy_ = WriteZeroPolicy((root_ / "private" / "zero.pt").string());
    ServerOptions options;
    options.service.checkpoint_dirs = {allowed_.string()};
    options.service.max_upload_bytes = 1 << 20;
    server_ = StartTestServer(options);
    ASSERT_NE(server_, nullptr);
    client_ = ConnectTo(*server_);
    ASSERT_NE(client_, nullptr);
  }
  void TearDown() override { server_->Shutdown(absl::Seconds(1)); }

  absl::Status RolloutOf(const std::string& path) {
    v1::RolloutRequest request;
    request.set_checkpoint_path(path);
    request.add_clips("deepmimic_walk");
    request.set_max_steps_per_clip(5);
    absl::Status status;
    // A 1 GiB file once took the server to 3.2 GB; now nothing above the upload limit is read.
    const int64_t growth = testing::PeakGrowthBytes([&] { status = client_->Rollout(request).status(); });
    EXPECT_LT(growth, int64_t{128} << 20) << path << ": peak resident memory rose by " << (growth >> 20) << " MiB";
    return status;
  }

  std::filesystem::path root_, allowed_;
  std::string policy_, outside_policy_;
  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<SimulationClient> client_;
};

TEST_F(CheckpointDirTest, FilesInTheDirectoryRunByAbsoluteOrRelativePath) {
  EXPECT_TRUE(RolloutOf(policy_).ok()) << RolloutOf(policy_);
  EXPECT_TRUE(RolloutOf("zero.pt").ok()) << RolloutOf("zero.pt");
  // Missing inside the directory: NOT_FOUND is no secret there.
  EXPECT_EQ(RolloutOf("other.pt").code(), absl::StatusCode::kNotFound);
}

TEST_F(CheckpointDirTest, AnyPathOutsideGetsOneAnswerWhetherItExistsOrNot) {
  const absl::Status existing = RolloutOf(outside_policy_);
  const absl::Status missing = RolloutOf((root_ / "private" / "missing.pt").string());
  const absl::Status system_file = RolloutOf("/etc/passwd");
  const absl::Status climbing = RolloutOf("../private/zero.pt");
  for (const absl::Status& status : {existing, missing, system_file, climbing}) {
    EXPECT_EQ(status.code(), absl::StatusCode::kPermissionDenied) << status;
    EXPECT_THAT(std::string(status.message()), HasSubstr("checkpoint_path"));
    EXPECT_EQ(status.message(), existing.message()) << "the answer must not tell which files exist";
  }
  // A link inside the directory that leads out of it is outside too.
  std::filesystem::create_symlink(outside_policy_, allowed_ / "link.pt");
  const absl::Status linked = RolloutOf("link.pt");
  EXPECT_EQ(linked.code(), absl::StatusCode::kPermissionDenied) << linked;
  EXPECT_EQ(linked.message(), existing.message());
}

TEST_F(CheckpointDirTest, NoRegularFilesAndOversizedFilesAreRefusedWithoutReadingThem) {
  // A FIFO would block a plain open until a writer came: the call must answer at once.
  const std::string fifo = (allowed_ / "pipe.pt").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const absl::Status piped = RolloutOf(fifo);
  EXPECT_EQ(piped.code(), absl::StatusCode::kInvalidArgument) << piped;
  EXPECT_THAT(std::string(piped.message()), HasSubstr("regular file"));
  // Larger than an upload may be (1 MiB here): refused before it is read.
  ASSERT_TRUE(WriteFileAtomically((allowed_ / "huge.pt").string(), std::string(64 << 20, 'x')).ok());
  const absl::Status huge = RolloutOf("huge.pt");
  EXPECT_EQ(huge.code(), absl::StatusCode::kResourceExhausted) << huge;
  EXPECT_THAT(std::string(huge.message()), HasSubstr("checkpoint_path"));
}

TEST(CheckpointDirDefaultTest, WithoutDirectoriesNoPathIsRead) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  v1::RolloutRequest request;
  request.set_checkpoint_path(WriteZeroPolicy(TestTempPath("service_hardening", "zero.pt")));
  request.add_clips("deepmimic_walk");
  const absl::Status status = client->Rollout(request).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kPermissionDenied) << status;
  EXPECT_THAT(std::string(status.message()), HasSubstr("bytes"));
  server->Shutdown(absl::Seconds(1));
}

TEST(StatusMessageTest, HugeClientStringsAreNotEchoedAndTheChannelSurvives) {
  auto server = StartTestServer();
  auto client = ConnectTo(*server);
  v1::SessionConfig config;
  config.set_num_envs(2);
  auto stream = client->OpenSession(config);
  ASSERT_TRUE(stream.ok()) << stream.status();
  const std::vector<float> zeros(2 * 69, 0.f);
  ASSERT_TRUE((*stream)->Step(zeros.data()).ok());

  v1::ReportFailuresRequest report;
  report.set_session_id(std::string(20000, 's'));
  const absl::Status unknown_session = client->ReportFailures(report).status();
  EXPECT_EQ(unknown_session.code(), absl::StatusCode::kNotFound) << unknown_session.message().substr(0, 200);
  EXPECT_LT(unknown_session.message().size(), kMaxClientMessage);

  report.set_session_id((*stream)->opened().session_id());
  v1::ClipFailure* failure = report.add_failures();
  failure->set_clip(std::string(1 << 20, 'c'));
  failure->set_frame(0);
  const absl::Status unknown_clip = client->ReportFailures(report).status();
  EXPECT_NE(unknown_clip.code(), absl::StatusCode::kOk);
  EXPECT_NE(unknown_clip.code(), absl::StatusCode::kResourceExhausted) << "the client's metadata limit was hit";
  EXPECT_LT(unknown_clip.message().size(), kMaxClientMessage);

  const absl::Status unknown_layout = client->Describe(std::string(1 << 20, 'l')).status();
  EXPECT_EQ(unknown_layout.code(), absl::StatusCode::kNotFound) << unknown_layout.message().substr(0, 200);
  EXPECT_LT(unknown_layout.message().size(), kMaxClientMessage);
  EXPECT_THAT(std::string(unknown_layout.message()), HasSubstr("1048576 bytes"));

  v1::RolloutRequest rollout;
  rollout.set_checkpoint_bytes("x");
  rollout.add_clips(std::string(50000, 'r'));
  const absl::Status unknown_rollout_clip = client->Rollout(rollout).status();
  EXPECT_NE(unknown_rollout_clip.code(), absl::StatusCode::kResourceExhausted);
  EXPECT_LT(unknown_rollout_clip.message().size(), kMaxClientMessage);

  // The documented maximum of 65536 does not fit the default 512 MiB message limit: refused up
  // front with the figure that does, instead of failing to send 608 MB.
  v1::SampleReferenceAmpRequest amp;
  amp.set_session_id((*stream)->opened().session_id());
  amp.set_num_samples(65536);
  absl::Status too_many_amp;
  const int64_t growth = testing::PeakGrowthBytes([&] { too_many_amp = client->SampleReferenceAmp(amp).status(); });
  EXPECT_LT(growth, int64_t{64} << 20) << "peak resident memory rose by " << (growth >> 20) << " MiB";
  EXPECT_EQ(too_many_amp.code(), absl::StatusCode::kInvalidArgument) << too_many_amp;
  EXPECT_THAT(std::string(too_many_amp.message()), HasSubstr("at most 57852"));

  // The session opened on the same channel before all this still steps.
  EXPECT_TRUE((*stream)->Step(zeros.data()).ok());
  EXPECT_TRUE((*stream)->Close().ok());
  server->Shutdown(absl::Seconds(1));
}

TEST(LibraryLimitTest, UploadsBeyondMaxLibraryClipsAreRefusedWholeAndLongNameListsEarly) {
  ServerOptions options;
  options.service.max_library_clips = 21;  // the shipped 20 and one more
  auto server = StartTestServer(options);
  auto client = ConnectTo(*server);
  auto walk = ReadFileToString(std::string(MODSKILL_REPO_DIR) + "/data/motions/source/deepmimic/humanoid3d_walk.txt", 1 << 20);
  ASSERT_TRUE(walk.ok());
  v1::AddMotionsRequest two;
  for (const char* name : {"walk_a", "walk_b"}) {
    v1::MotionUpload* upload = two.add_uploads();
    upload->set_file_name("humanoid3d_walk.txt");
    upload->set_name(name);
    upload->set_data(*walk);
  }
  const absl::Status refused = client->AddMotions(two).status();
  EXPECT_EQ(refused.code(), absl::StatusCode::kResourceExhausted) << refused;
  EXPECT_THAT(std::string(refused.message()), HasSubstr("--max_library_clips"));
  two.mutable_uploads()->RemoveLast();
  EXPECT_TRUE(client->AddMotions(two).ok());
  // A session config naming more clips than the library may hold is refused before any lookup.
  v1::SessionConfig config;
  config.set_num_envs(1);
  for (int i = 0; i < 22; ++i) config.add_motions("deepmimic_walk");
  const absl::Status listed = client->OpenSession(config).status();
  EXPECT_EQ(listed.code(), absl::StatusCode::kInvalidArgument) << listed;
  EXPECT_THAT(std::string(listed.message()), HasSubstr("motions"));
  server->Shutdown(absl::Seconds(1));
}

TEST(SampleReferenceAmpLimitTest, RequestsThatWouldNotFitTheMessageLimitAreRefusedNamingTheField) {
  ServerOptions options;
  options.max_message_bytes = 16 << 20;  // 1807 samples of 2320 floats fit
  auto server = StartTestServer(options);
  auto client = ConnectTo(*server);
  v1::SessionConfig config;
  config.set_num_envs(1);
  auto stream = client->OpenSession(config);
  ASSERT_TRUE(stream.ok()) << stream.status();
  v1::SampleReferenceAmpRequest request;
  request.set_session_id((*stream)->opened().session_id());
  const int64_t fit = ((int64_t{16} << 20) - 4096) / (2320 * 4);
  request.set_num_samples(static_cast<int>(fit));
  auto fits = client->SampleReferenceAmp(request);
  ASSERT_TRUE(fits.ok()) << fits.status();
  EXPECT_EQ(fits->amp_obs().shape(0), fit);
  request.set_num_samples(static_cast<int>(fit + 1));
  const absl::Status too_many = client->SampleReferenceAmp(request).status();
  EXPECT_EQ(too_many.code(), absl::StatusCode::kInvalidArgument) << too_many;
  EXPECT_THAT(std::string(too_many.message()), HasSubstr("num_samples"));
  EXPECT_THAT(std::string(too_many.message()), HasSubstr(absl::StrCat("at most ", fit)));
  EXPECT_THAT(std::string(too_many.message()), Not(HasSubstr("Sent message larger")));
  request.set_num_samples(65537);
  EXPECT_EQ(client->SampleReferenceAmp(request).status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE((*stream)->Close().ok());
  server->Shutdown(absl::Seconds(1));
}

}  // namespace
}  // namespace modskill
