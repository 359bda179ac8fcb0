// The learner's discriminator in the server's filter for generated clips
// (ReportFailuresRequest.discriminator): ModSkill keeps a generated clip only if the
// discriminator scores it >= 0.5 on 30 random frames.
#include <gmock/gmock.h>

#include "learner/amp_discriminator.h"
#include "learner/policy_export.h"
#include "learner/running_mean_std.h"
#include "tests/server_fixture.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

// A discriminator whose logit is `logit` whatever the input: AMP reward 1 (logit 1) or 0 (-1).
std::string ConstantScorer(float logit, int64_t width) {
  learner::AmpDiscriminator discriminator(width, std::vector<int64_t>{16});
  {
    torch::NoGradGuard no_grad;
    discriminator->mlp()->output_layer()->weight.zero_();
    discriminator->mlp()->output_layer()->bias.fill_(logit);
  }
  learner::RunningMeanStd norm(width);
  auto bytes = learner::ExportDiscriminatorScorer(*discriminator, *norm);
  EXPECT_TRUE(bytes.ok()) << bytes.status();
  return bytes.ok() ? *bytes : std::string();
}

class DiscriminatorFilterTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ServerOptions options;
    options.service.generation.failures_per_round = 4;
    options.service.generation.variants_per_round = 3;
    server_ = StartTestServer(options);
    ASSERT_NE(server_, nullptr);
    client_ = ConnectTo(*server_);
    ASSERT_NE(client_, nullptr);
    v1::SessionConfig config;
    config.set_num_envs(8);
    auto stream = client_->OpenSession(config);
    ASSERT_TRUE(stream.ok()) << stream.status();
    stream_ = *std::move(stream);
    width_ = stream_->spec().amp_history() * stream_->spec().amp_obs_per_frame();
  }
  void TearDown() override {
    if (stream_ != nullptr) EXPECT_TRUE(stream_->Close().ok());
    server_->Shutdown(absl::Seconds(1));
  }

  // A round's worth of right-arm failures on the walk, with `discriminator` attached.
  absl::StatusOr<v1::SamplerState> Report(const std::string& discriminator) {
    v1::ReportFailuresRequest request;
    request.set_session_id(stream_->opened().session_id());
    request.set_discriminator(discriminator);
    for (int k = 0; k < 4; ++k) {
      v1::ClipFailure* failure = request.add_failures();
      failure->set_clip("deepmimic_walk");
      failure->set_frame(-1);
      failure->set_terminated(true);
      for (int p = 0; p < stream_->spec().parts_size(); ++p) {
        failure->add_part_errors(stream_->spec().parts(p).name() == "R_Arm" ? 0.8f : 0.1f);
      }
    }
    auto state = client_->ReportFailures(request);
    server_->service().generation_worker().WaitIdle();
    return state;
  }

  v1::GenerationStats Generation() {
    auto stats = client_->GetStats();
    EXPECT_TRUE(stats.ok());
    return stats.ok() && stats->sessions_size() == 1 ? stats->sessions(0).generation() : v1::GenerationStats();
  }

  std::unique_ptr<RunningServer> server_;
  std::unique_ptr<SimulationClient> client_;
  std::unique_ptr<SimulationStream> stream_;
  int64_t width_ = 0;
};

TEST_F(DiscriminatorFilterTest, ClipsTheDiscriminatorRejectsNeverJoin) {
  ASSERT_TRUE(Report(ConstantScorer(-1.f, width_)).ok());
  v1::GenerationStats generation = Generation();
  EXPECT_EQ(generation.generated(), 0);
  EXPECT_EQ(generation.rejected(), 3);
  EXPECT_EQ(generation.rejected_by_check().at("discriminator"), 3) << generation.ShortDebugString();

  // A discriminator that likes everything: the next round's clips join.
  ASSERT_TRUE(Report(ConstantScorer(1.f, width_)).ok());
  generation = Generation();
  EXPECT_EQ(generation.generated(), 3) << generation.ShortDebugString();
  EXPECT_EQ(generation.live_generated_clips(), 3);
}

TEST_F(DiscriminatorFilterTest, ABadDiscriminatorIsAnErrorAndRecordsNothing) {
  auto state = Report("not a TorchScript archive");
  EXPECT_EQ(state.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(state.status().message()), HasSubstr("discriminator"));
  // One for another AMP size.
  state = Report(ConstantScorer(1.f, width_ + 1));
  EXPECT_EQ(state.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(Generation().requests(), 0);
  auto stats = client_->GetStats();
  ASSERT_TRUE(stats.ok());
  EXPECT_EQ(stats->failure_reports(), 0);
}

}  // namespace
}  // namespace modskill
