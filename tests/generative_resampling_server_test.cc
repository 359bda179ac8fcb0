// Generative resampling (ModSkill's active skill learning): the session motion set's rounds,
// names and eviction; the server adding variants of failed clips to a live session; and the
// external MotionGenerator path, including a generator that is down, slow or malformed.
#include <cstring>
#include <filesystem>
#include <optional>
#include <thread>

#include <gmock/gmock.h>
#include <grpcpp/grpcpp.h>

#include "absl/strings/match.h"
#include "absl/time/clock.h"
#include "server/core/curriculum/session_motion_set.h"
#include "server/core/motion/clip_file.h"
#include "server/service/external_motion_generator.h"
#include "tests/server_fixture.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;

std::shared_ptr<const MotionLibrary> TwoClips() {
  auto library = DefaultMotions()->Subset({"deepmimic_walk", "deepmimic_run"});
  EXPECT_TRUE(library.ok()) << library.status();
  return std::make_shared<const MotionLibrary>(*std::move(library));
}

MotionVariant FakeVariant(const MotionClip& parent, int part) {
  MotionVariant variant;
  variant.clip = parent;
  variant.provenance = VariantProvenance{parent.name, "test", part, 7};
  return variant;
}

const std::vector<std::string> kParts = {"L_Leg", "R_Leg", "Torso", "L_Arm", "R_Arm"};

TEST(SessionMotionSetTest, RoundsComeAfterEnoughFailuresAndAlternatePartAndWholeBody) {
  GenerationOptions options;
  options.failures_per_round = 3;
  options.variants_per_round = 2;
  SessionMotionSet set(TwoClips(), kParts, options, 1);
  // Part errors say the right arm is lost.
  const std::vector<float> arm_errors = {0.1f, 0.1f, 0.1f, 0.1f, 0.9f};
  std::vector<SessionMotionSet::FailureReport> failures = {{0, arm_errors}, {0, arm_errors}};
  EXPECT_TRUE(set.PlanRounds(failures).empty());
  auto rounds = set.PlanRounds({{0, arm_errors}, {1, {}}});
  ASSERT_EQ(rounds.size(), 1u);
  EXPECT_EQ(rounds[0].parent->name, "deepmimic_walk");
  EXPECT_EQ(rounds[0].part, 4);  // R_Arm: the largest mean error
  EXPECT_EQ(rounds[0].count, 2);
  // In flight: more failures start no second round until it is committed.
  EXPECT_TRUE(set.PlanRounds({{0, arm_errors}, {0, arm_errors}, {0, arm_errors}}).empty());
  set.Commit("deepmimic_walk", {}, {1.0, 1.0});
  rounds = set.PlanRounds({{0, arm_errors}, {0, arm_errors}, {0, arm_errors}});
  ASSERT_EQ(rounds.size(), 1u);
  EXPECT_EQ(rounds[0].part, -1);  // the next round is whole body
  const uint64_t first_seed = rounds[0].seed;
  set.Commit("deepmimic_walk", {}, {1.0, 1.0});
  rounds = set.PlanRounds({{0, arm_errors}, {0, arm_errors}, {0, arm_errors}});
  ASSERT_EQ(rounds.size(), 1u);
  EXPECT_NE(rounds[0].seed, first_seed);
}

TEST(SessionMotionSetTest, TheDefaultCapIsTheNumberOfOriginalClips) {
  GenerationOptions options;
  ASSERT_EQ(options.max_generated_clips, -1);
  EXPECT_TRUE(ValidateGenerationOptions(options).ok());
  SessionMotionSet set(TwoClips(), kParts, options, 1);
  EXPECT_EQ(set.options().max_generated_clips, 2);
  const MotionClip& walk = set.library()->clip(0);
  set.Commit("deepmimic_walk", {FakeVariant(walk, 4), FakeVariant(walk, 4), FakeVariant(walk, 4)}, {1, 1});
  EXPECT_EQ(set.live_generated(), 2);
  options.max_generated_clips = -2;
  EXPECT_THAT(std::string(ValidateGenerationOptions(options).message()), HasSubstr("--max_generated_clips"));
}

TEST(SessionMotionSetTest, NoRoundsWhenDisabledOrCappedAtZero) {
  GenerationOptions options;
  options.failures_per_round = 1;
  options.enabled = false;
  SessionMotionSet disabled(TwoClips(), kParts, options, 1);
  EXPECT_TRUE(disabled.PlanRounds({{0, {}}, {1, {}}}).empty());
  options.enabled = true;
  options.max_generated_clips = 0;
  SessionMotionSet capped(TwoClips(), kParts, options, 1);
  EXPECT_TRUE(capped.PlanRounds({{0, {}}, {1, {}}}).empty());
}

TEST(SessionMotionSetTest, CommitNamesUniquelyAndEvictsLeastSampledThenOldest) {
  GenerationOptions options;
  options.max_generated_clips = 3;
  SessionMotionSet set(TwoClips(), kParts, options, 1);
  const MotionClip& walk = set.library()->clip(0);
  MotionSetChange change = set.Commit("deepmimic_walk", {FakeVariant(walk, 4), FakeVariant(walk, 4)}, {1, 1});
  ASSERT_EQ(change.added.size(), 2u);
  EXPECT_EQ(change.added[0].name, "deepmimic_walk~R_Arm~2");
  EXPECT_EQ(change.added[1].name, "deepmimic_walk~R_Arm~3");
  EXPECT_EQ(change.previous_slot, (std::vector<int>{0, 1, -1, -1}));
  EXPECT_EQ(set.clip_ids(), (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(set.library()->size(), 4);
  EXPECT_EQ(set.Find("deepmimic_walk~R_Arm~3"), 3);
  ASSERT_TRUE(set.info(3).provenance.has_value());
  EXPECT_EQ(set.info(3).provenance->parent, "deepmimic_walk");

  // Two more with a cap of 3: one must go. Slot 3 is sampled less than slot 2, so it leaves
  // although it is not the oldest.
  change = set.Commit("deepmimic_walk", {FakeVariant(walk, -1), FakeVariant(walk, -1)}, {1, 1, 5.0, 0.5});
  EXPECT_EQ(change.removed_ids, (std::vector<int>{3}));
  EXPECT_EQ(change.previous_slot, (std::vector<int>{0, 1, 2, -1, -1}));
  EXPECT_EQ(set.clip_ids(), (std::vector<int>{0, 1, 2, 4, 5}));
  EXPECT_EQ(set.info(3).name, "deepmimic_walk~w~4");
  EXPECT_EQ(set.Find("deepmimic_walk~R_Arm~3"), -1);
  EXPECT_TRUE(set.WasEvicted("deepmimic_walk~R_Arm~3"));
  EXPECT_FALSE(set.WasEvicted("deepmimic_walk"));
  EXPECT_EQ(set.live_generated(), 3);

  // Equal weights: the oldest generated clip (id 2) leaves first; originals never do.
  change = set.Commit("deepmimic_run", {FakeVariant(set.library()->clip(1), -1)}, {1, 1, 1, 1, 1});
  EXPECT_EQ(change.removed_ids, (std::vector<int>{2}));
  EXPECT_EQ(set.clip_ids(), (std::vector<int>{0, 1, 4, 5, 6}));
  EXPECT_EQ(set.library()->clip(4).name, "deepmimic_run~w~6");
}

// ---------------------------------------------------------------------------------------------
// The server

int PartIndex(const v1::EnvSpec& spec, const std::string& name) {
  for (int p = 0; p < spec.parts_size(); ++p) {
    if (spec.parts(p).name() == name) return p;
  }
  return -1;
}

int ClipIndex(const v1::SessionOpened& opened, const std::string& name) {
  for (int c = 0; c < opened.clip_names_size(); ++c) {
    if (opened.clip_names(c) == name) return c;
  }
  return -1;
}

const v1::SessionStats* FindSession(const v1::ServerStats& stats, const std::string& id) {
  for (const v1::SessionStats& session : stats.sessions()) {
    if (session.session_id() == id) return &session;
  }
  return nullptr;
}

std::vector<int32_t> Int32s(const v1::Tensor& tensor) {
  std::vector<int32_t> values(tensor.data().size() / sizeof(int32_t));
  std::memcpy(values.data(), tensor.data().data(), values.size() * sizeof(int32_t));
  return values;
}

// `count` terminated reports on `clip` whose part errors single out `worst_part`.
v1::ReportFailuresRequest ArmFailures(const std::string& session_id, const std::string& clip, int count,
                                      int num_parts, int worst_part) {
  v1::ReportFailuresRequest request;
  request.set_session_id(session_id);
  for (int k = 0; k < count; ++k) {
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip(clip);
    failure->set_frame(-1);
    failure->set_terminated(true);
    for (int p = 0; p < num_parts; ++p) failure->add_part_errors(p == worst_part ? 0.8f : 0.1f);
  }
  return request;
}

class GenerativeServerTest : public ::testing::Test {
 protected:
  void Start(const std::string& generator = "", absl::Duration timeout = absl::Seconds(5), int cap = 64,
             const std::string& save_dir = "", int64_t max_saved = 10000) {
    ServerOptions options;
    options.service.generated_clip_dir = save_dir;
    options.service.max_saved_generated_clips = max_saved;
    options.service.max_envs_per_session = 64;
    options.service.generation.failures_per_round = 4;
    options.service.generation.variants_per_round = 3;
    options.service.generation.max_generated_clips = cap;
    options.service.generator_address = generator;
    options.service.generator_timeout = timeout;
    server_ = StartTestServer(options);
    ASSERT_NE(server_, nullptr);
    client_ = ConnectTo(*server_);
    ASSERT_NE(client_, nullptr);
    v1::SessionConfig config;
    config.set_num_envs(32);
    config.set_seed(5);
    auto stream = client_->OpenSession(config);
    ASSERT_TRUE(stream.ok()) << stream.status();
    stream_ = *std::move(stream);
    session_id_ = stream_->opened().session_id();
    arm_ = PartIndex(stream_->spec(), "R_Arm");
    ASSERT_GE(arm_, 0);
    walk_ = ClipIndex(stream_->opened(), "deepmimic_walk");
    ASSERT_GE(walk_, 0);
  }
  void TearDown() override {
    if (stream_ != nullptr) EXPECT_TRUE(stream_->Close().ok());
    if (server_ != nullptr) server_->Shutdown(absl::Seconds(1));
  }

  // Reports a round's worth of arm failures on the walk and waits for the round to finish.
  void FailTheWalk() {
    auto state = client_->ReportFailures(
        ArmFailures(session_id_, "deepmimic_walk", 4, stream_->spec().parts_size(), arm_));
    ASSERT_TRUE(state.ok()) << state.status();
    server_->service().generation_worker().WaitIdle();
  }

  // Steps with zero actions until a step announces a motion set change (at most `steps`); a
  // copy, since the stream reuses its result message.
  std::optional<v1::MotionSetUpdate> StepUntilUpdate(int steps = 5) {
    std::vector<float> zeros(static_cast<size_t>(stream_->num_envs()) * stream_->spec().action_size(), 0.f);
    for (int s = 0; s < steps; ++s) {
      if (!stream_->Step(zeros.data()).ok()) return std::nullopt;
      if (stream_->result().has_motion_set_update()) return stream_->result().motion_set_update();
    }
    return std::nullopt;
  }

  v1::GenerationStats Generation() {
    auto stats = client_->GetStats();
    EXPECT_TRUE(stats.ok()) << stats.status();
    const v1::SessionStats* session = stats.ok() ? FindSession(*stats, session_id_) : nullptr;
    EXPECT_NE(session, nullptr);
    return session != nullptr ? session->generation() : v1::GenerationStats();
  }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<SimulationClient> client_;
  std::unique_ptr<SimulationStream> stream_;
  std::string session_id_;
  int arm_ = -1;
  int walk_ = -1;
};

TEST_F(GenerativeServerTest, FailedClipGetsVariantsThatEnvsThenTrain) {
  const std::string save_dir = std::string(MODSKILL_TEST_TMP_DIR) + "/generated_clips";
  std::filesystem::remove_all(save_dir);
  Start("", absl::Seconds(5), 64, save_dir);
  const int originals = stream_->opened().clip_names_size();
  FailTheWalk();
  const std::optional<v1::MotionSetUpdate> update = StepUntilUpdate();
  ASSERT_TRUE(update.has_value()) << "no motion set update after a round";
  ASSERT_EQ(update->added_size(), 3);
  EXPECT_EQ(update->removed_clip_ids_size(), 0);
  std::vector<int> ids;
  for (const v1::SessionClip& clip : update->added()) {
    EXPECT_GE(clip.clip_id(), originals);
    EXPECT_EQ(clip.provenance().parent(), "deepmimic_walk");
    EXPECT_EQ(clip.provenance().part(), "R_Arm");  // the part the failures singled out
    EXPECT_EQ(clip.provenance().generator(), kBuiltinVariantGenerator);
    EXPECT_TRUE(absl::StartsWith(clip.name(), "deepmimic_walk~R_Arm~")) << clip.name();
    EXPECT_EQ(stream_->clip_name(clip.clip_id()), clip.name());
    ids.push_back(clip.clip_id());
    // --save_generated: the clip is on disk under its session name.
    auto saved = ReadClipFile(save_dir + "/" + session_id_ + "/" + clip.name() + ".msclip", DefaultSpec());
    ASSERT_TRUE(saved.ok()) << saved.status();
    EXPECT_EQ(saved->name, clip.name());
  }
  EXPECT_EQ(stream_->live_clips(), originals + 3);

  v1::GenerationStats generation = Generation();
  EXPECT_TRUE(generation.enabled());
  EXPECT_EQ(generation.requests(), 1);
  EXPECT_EQ(generation.generated(), 3);
  EXPECT_EQ(generation.live_generated_clips(), 3);
  EXPECT_EQ(generation.rejected(), 0);
  // The variants inherit their parent's failure count, so envs start on them right away.
  std::vector<float> zeros(static_cast<size_t>(stream_->num_envs()) * stream_->spec().action_size(), 0.f);
  int generated_starts = 0;
  for (int s = 0; s < 60 && generated_starts == 0; ++s) {
    ASSERT_TRUE(stream_->Step(zeros.data()).ok());
    for (int32_t id : Int32s(stream_->result().clip_id())) generated_starts += id >= originals;
  }
  EXPECT_GT(generated_starts, 0);
  // A generated clip can be reported on by name like any other.
  v1::ReportFailuresRequest request = ArmFailures(session_id_, update->added(0).name(), 1, 5, arm_);
  auto state = client_->ReportFailures(request);
  ASSERT_TRUE(state.ok()) << state.status();
  ASSERT_EQ(state->clips_size(), originals + 3);
  EXPECT_EQ(state->clips(originals).clip_id(), ids[0]);
  EXPECT_EQ(state->clips(originals).failures(), 1);
  EXPECT_EQ(state->clips(originals).provenance().parent(), "deepmimic_walk");
}

// --max_saved_generated_clips bounds what --save_generated writes; the session still gets them all.
TEST_F(GenerativeServerTest, SavingGeneratedClipsStopsAtItsLimit) {
  const std::string save_dir = std::string(MODSKILL_TEST_TMP_DIR) + "/generated_clips_capped";
  std::filesystem::remove_all(save_dir);
  Start("", absl::Seconds(5), 64, save_dir, /*max_saved=*/2);
  FailTheWalk();
  const std::optional<v1::MotionSetUpdate> update = StepUntilUpdate();
  ASSERT_TRUE(update.has_value());
  EXPECT_EQ(update->added_size(), 3);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(save_dir + "/" + session_id_)) files += entry.is_regular_file();
  EXPECT_EQ(files, 2);
}

TEST_F(GenerativeServerTest, TheCapEvictsAndReportsOnEvictedClipsAreNotErrors) {
  Start("", absl::Seconds(5), /*cap=*/4);
  FailTheWalk();  // 3 arm variants
  ASSERT_TRUE(StepUntilUpdate().has_value());
  FailTheWalk();  // 3 whole-body variants: 2 of the first 3 must leave
  const std::optional<v1::MotionSetUpdate> update = StepUntilUpdate();
  ASSERT_TRUE(update.has_value());
  const v1::GenerationStats generation = Generation();
  const int joined = static_cast<int>(generation.generated());
  EXPECT_EQ(generation.live_generated_clips(), std::min(joined, 4));
  EXPECT_EQ(generation.evicted(), std::max(0, joined - 4));
  EXPECT_EQ(update->removed_clip_ids_size(), std::max(0, joined - 4));
  ASSERT_GT(update->removed_clip_ids_size(), 0) << "whole-body variants were all rejected: "
                                                 << generation.ShortDebugString();
  const std::string evicted = stream_->clip_name(update->removed_clip_ids(0));
  ASSERT_FALSE(evicted.empty());
  auto state = client_->ReportFailures(ArmFailures(session_id_, evicted, 1, 5, arm_));
  EXPECT_TRUE(state.ok()) << state.status();
  // A name that never was a clip of the session still is an error naming the field.
  auto unknown = client_->ReportFailures(ArmFailures(session_id_, "no_such_clip", 1, 5, arm_));
  EXPECT_EQ(unknown.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(unknown.status().message()), HasSubstr("failures[0].clip"));
}

TEST_F(GenerativeServerTest, NoGenerativeKeepsTheMotionSetFixed) {
  ServerOptions options;
  options.service.generation.enabled = false;
  options.service.generation.failures_per_round = 1;
  server_ = StartTestServer(options);
  ASSERT_NE(server_, nullptr);
  client_ = ConnectTo(*server_);
  v1::SessionConfig config;
  config.set_num_envs(8);
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  stream_ = *std::move(stream);
  session_id_ = stream_->opened().session_id();
  auto state = client_->ReportFailures(ArmFailures(session_id_, "deepmimic_walk", 20, 5, 4));
  ASSERT_TRUE(state.ok());
  server_->service().generation_worker().WaitIdle();
  EXPECT_FALSE(StepUntilUpdate(3).has_value());
  const v1::GenerationStats generation = Generation();
  EXPECT_FALSE(generation.enabled());
  EXPECT_EQ(generation.requests(), 0);
  EXPECT_EQ(generation.live_generated_clips(), 0);
}

// ---------------------------------------------------------------------------------------------
// External generators

enum class FakeMode { kGood, kPlantedBadClip, kWrongBodies, kSlow };

// A MotionGenerator that bends the requested bodies a little (or misbehaves, by mode).
class FakeGenerator final : public v1::MotionGenerator::Service {
 public:
  explicit FakeGenerator(FakeMode mode) : mode_(mode) {}
  grpc::Status Generate(grpc::ServerContext* context, const v1::GenerateMotionRequest* request,
                        v1::GenerateMotionResponse* reply) override {
    ++calls_;
    last_text_ = request->text();
    last_part_ = request->part();
    if (mode_ == FakeMode::kSlow) std::this_thread::sleep_for(std::chrono::milliseconds(1500));
    const HumanoidSpec& spec = DefaultSpec();
    auto parent = FromMotionData(spec, request->parent(), "parent");
    if (!parent.ok()) return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, std::string(parent.status().message()));
    for (int k = 0; k < request->count(); ++k) {
      MotionClip clip = *parent;
      for (int f = 0; f < clip.num_frames; ++f) {
        for (int b = 1; b < clip.num_bodies; ++b) {
          if (!request->part_mask(b)) continue;
          clip.local(f, b) = clip.local(f, b) * Quat(Eigen::AngleAxisd(0.05 * (k + 1), Vec3::UnitZ()));
        }
      }
      if (mode_ == FakeMode::kPlantedBadClip && k == 0) {
        // One frame where every masked joint flips by 3 rad: the arm teleports (a velocity spike;
        // arm hinges have no range to leave, PHC gives them +-720 deg).
        const int f = clip.num_frames / 2;
        for (int b = 1; b < clip.num_bodies; ++b) {
          if (request->part_mask(b)) clip.local(f, b) = clip.local(f, b) * Quat(Eigen::AngleAxisd(3.0, Vec3::UnitX()));
        }
      }
      v1::MotionData* data = reply->add_clips();
      ToMotionData(spec, clip, data);
      if (mode_ == FakeMode::kWrongBodies) data->set_body_names(3, "Tail");
    }
    reply->set_generator("fake");
    return grpc::Status::OK;
  }
  std::atomic<int> calls_{0};
  std::string last_text_, last_part_;

 private:
  FakeMode mode_;
};

class ExternalGeneratorTest : public GenerativeServerTest {
 protected:
  void StartGenerator(FakeMode mode) {
    fake_ = std::make_unique<FakeGenerator>(mode);
    grpc::ServerBuilder builder;
    int port = 0;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
    builder.RegisterService(fake_.get());
    generator_ = builder.BuildAndStart();
    ASSERT_NE(generator_, nullptr);
    address_ = "127.0.0.1:" + std::to_string(port);
  }
  void TearDown() override {
    GenerativeServerTest::TearDown();
    if (generator_ != nullptr) generator_->Shutdown(std::chrono::system_clock::now());
  }
  std::unique_ptr<FakeGenerator> fake_;
  std::unique_ptr<grpc::Server> generator_;
  std::string address_;
};

TEST_F(ExternalGeneratorTest, ClipsFromTheGeneratorJoinWithItsNameAndTheCaption) {
  StartGenerator(FakeMode::kGood);
  Start(address_);
  FailTheWalk();
  const std::optional<v1::MotionSetUpdate> update = StepUntilUpdate();
  ASSERT_TRUE(update.has_value());
  ASSERT_EQ(update->added_size(), 3);
  for (const v1::SessionClip& clip : update->added()) EXPECT_EQ(clip.provenance().generator(), "fake");
  EXPECT_EQ(fake_->calls_, 1);
  EXPECT_EQ(fake_->last_part_, "R_Arm");
  EXPECT_FALSE(fake_->last_text_.empty()) << "the request carries the parent's caption";
  const v1::GenerationStats generation = Generation();
  EXPECT_EQ(generation.generator_errors(), 0);
  EXPECT_EQ(generation.generated(), 3);
}

TEST_F(ExternalGeneratorTest, ThePlausibilityFilterRejectsAPlantedBadClip) {
  StartGenerator(FakeMode::kPlantedBadClip);
  Start(address_);
  FailTheWalk();
  const v1::GenerationStats generation = Generation();
  EXPECT_EQ(generation.generator_errors(), 0);
  EXPECT_EQ(generation.rejected(), 1) << generation.ShortDebugString();
  EXPECT_EQ(generation.rejected_by_check().count("body_speed"), 1u) << generation.ShortDebugString();
  EXPECT_EQ(generation.generated(), 2);
}

TEST_F(ExternalGeneratorTest, AMalformedReplyIsAnErrorAndTheBuiltInGeneratorStepsIn) {
  StartGenerator(FakeMode::kWrongBodies);
  Start(address_);
  FailTheWalk();
  const v1::GenerationStats generation = Generation();
  EXPECT_EQ(generation.generator_errors(), 1);
  EXPECT_EQ(generation.builtin_fallbacks(), 1);
  EXPECT_THAT(generation.last_generator_error(), HasSubstr("body_names[3]"));
  const std::optional<v1::MotionSetUpdate> update = StepUntilUpdate();
  ASSERT_TRUE(update.has_value());
  for (const v1::SessionClip& clip : update->added()) {
    EXPECT_EQ(clip.provenance().generator(), kBuiltinVariantGenerator);
  }
}

TEST_F(ExternalGeneratorTest, ASlowGeneratorTimesOutWithoutStallingTheSession) {
  StartGenerator(FakeMode::kSlow);
  Start(address_, absl::Milliseconds(200));
  auto state = client_->ReportFailures(ArmFailures(session_id_, "deepmimic_walk", 4, 5, arm_));
  ASSERT_TRUE(state.ok());
  // The session steps on while the generator sleeps.
  std::vector<float> zeros(static_cast<size_t>(stream_->num_envs()) * stream_->spec().action_size(), 0.f);
  const absl::Time start = absl::Now();
  for (int s = 0; s < 3; ++s) ASSERT_TRUE(stream_->Step(zeros.data()).ok());
  server_->service().generation_worker().WaitIdle();
  const v1::GenerationStats generation = Generation();
  EXPECT_EQ(generation.generator_errors(), 1);
  EXPECT_THAT(generation.last_generator_error(), HasSubstr("Deadline"));
  EXPECT_EQ(generation.builtin_fallbacks(), 1);
  EXPECT_GT(generation.generated(), 0);
  EXPECT_LT(absl::Now() - start, absl::Seconds(10));
}

TEST_F(ExternalGeneratorTest, AGeneratorThatIsDownIsSurvived) {
  // Nothing listens there: a port bound and released.
  StartGenerator(FakeMode::kGood);
  const std::string dead = address_;
  generator_->Shutdown(std::chrono::system_clock::now());
  generator_.reset();
  Start(dead, absl::Seconds(2));
  FailTheWalk();
  FailTheWalk();
  const v1::GenerationStats generation = Generation();
  EXPECT_EQ(generation.generator_errors(), 2);
  EXPECT_EQ(generation.builtin_fallbacks(), 2);
  EXPECT_FALSE(generation.last_generator_error().empty());
  EXPECT_GT(generation.generated(), 0);
  ASSERT_TRUE(StepUntilUpdate().has_value());
}

}  // namespace
}  // namespace modskill
