// The gRPC server end to end, the curriculum side: failure reports, adaptive clip sampling (and
// its ablations), per-part errors in step results, reference AMP samples.

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <thread>

#include <gmock/gmock.h>

#include "absl/time/clock.h"
#include "common/atomic_file.h"
#include "common/wire/tensor_codec.h"
#include "server/core/curriculum/adaptive_sampler.h"
#include "tests/server_fixture.h"
#include "tests/simulation_server_fixture.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

TEST_F(SimulationServerTest, ReportFailuresValidatesAndStores) {
  v1::SessionConfig config = Config(2);
  config.add_motions("deepmimic_walk");
  config.add_motions("deepmimic_run");
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  v1::ReportFailuresRequest request;
  request.set_session_id((*stream)->opened().session_id());
  v1::ClipFailure* failure = request.add_failures();
  failure->set_clip("deepmimic_run");
  failure->set_frame(7);
  failure->set_terminated(true);
  failure->set_steps(12);
  for (float e : {0.1f, 0.2f, 0.3f, 0.05f, 0.05f}) failure->add_part_errors(e);
  v1::ClipFailure* success = request.add_failures();
  success->set_clip("deepmimic_walk");
  success->set_frame(-1);
  success->set_steps(30);
  auto state = client_->ReportFailures(request);
  ASSERT_TRUE(state.ok()) << state.status();
  ASSERT_EQ(state->clips_size(), 2);
  EXPECT_EQ(state->clips(1).clip(), "deepmimic_run");
  EXPECT_EQ(state->clips(1).failures(), 1);
  EXPECT_EQ(state->clips(1).last_failed_frame(), 7);
  EXPECT_NEAR(state->clips(1).mean_part_errors(2), 0.3f, 1e-6);
  EXPECT_EQ(state->clips(1).reported_steps(), 12);
  EXPECT_EQ(state->clips(0).successes(), 1);
  EXPECT_EQ(state->clips(0).reported_steps(), 30);
  EXPECT_NEAR(state->clips(0).probability() + state->clips(1).probability(), 1.0, 1e-9);
  EXPECT_EQ(state->reports(), 2);

  auto expect = [&](v1::ReportFailuresRequest bad, absl::StatusCode code, const std::string& needle) {
    auto result = client_->ReportFailures(bad);
    ASSERT_FALSE(result.ok()) << needle;
    EXPECT_EQ(result.status().code(), code) << result.status();
    EXPECT_THAT(std::string(result.status().message()), HasSubstr(needle));
  };
  v1::ReportFailuresRequest bad = request;
  bad.set_session_id("s999");
  expect(bad, absl::StatusCode::kNotFound, "session_id");
  bad = request;
  bad.mutable_failures(1)->set_clip("deepmimic_backflip");  // in the library, not in the session
  expect(bad, absl::StatusCode::kNotFound, "failures[1].clip");
  bad = request;
  bad.mutable_failures(0)->add_part_errors(0.1f);
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[0].part_errors");
  bad = request;
  bad.mutable_failures(0)->set_part_errors(1, std::nanf(""));
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[0].part_errors[1]");
  bad = request;
  bad.mutable_failures(0)->set_frame(100000);
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[0].frame");
  bad = request;
  bad.mutable_failures(1)->set_steps(-3);
  expect(bad, absl::StatusCode::kInvalidArgument, "failures[1].steps");
  // Rejected reports recorded nothing.
  auto unchanged = client_->ReportFailures(request);
  ASSERT_TRUE(unchanged.ok());
  EXPECT_EQ(unchanged->clips(1).failures(), 2);
  EXPECT_EQ(unchanged->reports(), 4);
}

std::vector<int32_t> Int32s(const v1::Tensor& tensor) {
  std::vector<int32_t> values(tensor.data().size() / sizeof(int32_t));
  std::memcpy(values.data(), tensor.data().data(), values.size() * sizeof(int32_t));
  return values;
}

const v1::SessionStats* FindSession(const v1::ServerStats& stats, const std::string& id) {
  for (const v1::SessionStats& session : stats.sessions()) {
    if (session.session_id() == id) return &session;
  }
  return nullptr;
}

// Adaptive sampling end to end: failures of one clip raise its probability in the reply and in
// GetStats, and the session's envs then start their episodes on it far more often.
TEST_F(SimulationServerTest, ReportedFailuresSteerWhichClipsEnvsStartOn) {
  const int n = 64;
  auto stream = client_->OpenSession(Config(n, 11));
  ASSERT_TRUE(stream.ok()) << stream.status();
  const v1::SessionOpened& opened = (*stream)->opened();
  const int num_clips = opened.clip_names_size();
  ASSERT_GE(num_clips, 10);
  const int target = 3;
  const std::string target_name = opened.clip_names(target);

  v1::ReportFailuresRequest request;
  request.set_session_id(opened.session_id());
  for (int k = 0; k < 50; ++k) {
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip(target_name);
    failure->set_frame(-1);
    failure->set_terminated(true);
  }
  v1::ClipFailure* success = request.add_failures();  // a success elsewhere changes little
  success->set_clip(opened.clip_names(0));
  success->set_frame(-1);
  auto state = client_->ReportFailures(request);
  ASSERT_TRUE(state.ok()) << state.status();
  ASSERT_EQ(state->clips_size(), num_clips);
  double total = 0;
  for (int c = 0; c < num_clips; ++c) {
    total += state->clips(c).probability();
    EXPECT_GE(state->clips(c).probability(), kDefaultSamplingFloor / num_clips * (1 - 1e-9)) << c;
  }
  EXPECT_NEAR(total, 1.0, 1e-9);
  EXPECT_EQ(state->clips(target).clip(), target_name);
  EXPECT_EQ(state->clips(target).failures(), 50);
  EXPECT_NEAR(state->clips(target).weight(), 50 + kFailureCountEpsilon, 1e-9);
  // Default floor 0.2: the failing clip takes the 80 % that follows the failures.
  EXPECT_NEAR(state->clips(target).probability(), 1 - (num_clips - 1) * kDefaultSamplingFloor / num_clips, 1e-6);

  auto stats = client_->GetStats();
  ASSERT_TRUE(stats.ok());
  const v1::SessionStats* session = FindSession(*stats, opened.session_id());
  ASSERT_NE(session, nullptr);
  ASSERT_EQ(session->clips_size(), num_clips);
  for (int c = 0; c < num_clips; ++c) {
    EXPECT_EQ(session->clips(c).clip(), opened.clip_names(c));
    EXPECT_DOUBLE_EQ(session->clips(c).probability(), state->clips(c).probability());
  }
  EXPECT_EQ(session->clips(target).failures(), 50);
  EXPECT_EQ(session->clips(0).successes(), 1);

  // Zero actions: the humanoids fall within a few dozen steps and restart on a drawn clip.
  std::vector<float> zeros(static_cast<size_t>(n) * 69, 0.f);
  int starts = 0, target_starts = 0;
  for (int s = 0; s < 50; ++s) {
    ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
    const v1::StepResult& result = (*stream)->result();
    const std::string& done = result.done().data();
    const std::vector<int32_t> clip_id = Int32s(result.clip_id());
    ASSERT_EQ(clip_id.size(), static_cast<size_t>(n));
    for (int i = 0; i < n; ++i) {
      if (!done[i]) continue;
      ++starts;
      target_starts += clip_id[i] == target;
    }
  }
  ASSERT_GE(starts, 500);
  const double share = static_cast<double>(target_starts) / starts;
  EXPECT_GT(share, 0.5) << target_starts << " of " << starts << " episodes (uniform: " << 1.0 / num_clips << ")";
  // Every restart is a fresh draw: the share estimates the reported probability (sd ~0.012 here).
  EXPECT_NEAR(share, state->clips(target).probability(), 0.06);
  EXPECT_TRUE((*stream)->Close().ok());
}

TEST_F(SimulationServerTest, SuccessesBringTheProbabilityBack) {
  v1::SessionConfig config = Config(2);
  for (const char* clip : {"deepmimic_walk", "deepmimic_run", "deepmimic_jog", "deepmimic_kick"}) config.add_motions(clip);
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  auto report = [&](bool terminated, int times) {
    v1::ReportFailuresRequest request;
    request.set_session_id((*stream)->opened().session_id());
    for (int k = 0; k < times; ++k) {
      v1::ClipFailure* failure = request.add_failures();
      failure->set_clip("deepmimic_kick");
      failure->set_frame(-1);
      failure->set_terminated(terminated);
    }
    auto state = client_->ReportFailures(request);
    EXPECT_TRUE(state.ok()) << state.status();
    return state.ok() ? state->clips(3).probability() : -1.0;
  };
  // Count 5 against ε for the others: all but the floor (3 x 0.2 / 4) goes to the failing clip.
  const double failed = report(true, 5);
  EXPECT_NEAR(failed, 0.85, 1e-9);
  // 60 successes: count 5 x 0.9^60 = 0.009, close enough to the others' ε that they rise above the floor.
  const double recovering = report(false, 60);
  EXPECT_LT(recovering, failed - 0.05);
  EXPECT_NEAR(report(false, 200), 0.25, 1e-3);
  // Stepping applies the weights without disturbing the stream.
  std::vector<float> zeros(2 * 69, 0.f);
  for (int s = 0; s < 3; ++s) ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
  EXPECT_TRUE((*stream)->Close().ok());
}

TEST(SimulationServerSamplingTest, UniformAblationNeverMovesAndTheOtherSchemesFollowFailures) {
  for (SamplingScheme scheme :
       {SamplingScheme::kUniform, SamplingScheme::kDecayOnSuccess, SamplingScheme::kFailureRate}) {
    ServerOptions options;
    options.service.sampling = scheme;
    auto server = StartTestServer(options);
    ASSERT_NE(server, nullptr);
    auto client = ConnectTo(*server);
    ASSERT_NE(client, nullptr);
    v1::SessionConfig config = Config(2);
    for (const char* clip : {"deepmimic_walk", "deepmimic_run", "deepmimic_jog"}) config.add_motions(clip);
    auto stream = client->OpenSession(config);
    ASSERT_TRUE(stream.ok());
    v1::ReportFailuresRequest request;
    request.set_session_id((*stream)->opened().session_id());
    for (int k = 0; k < 20; ++k) {
      v1::ClipFailure* success = request.add_failures();
      success->set_clip(k % 2 ? "deepmimic_walk" : "deepmimic_jog");
      success->set_frame(-1);
    }
    v1::ClipFailure* failure = request.add_failures();
    failure->set_clip("deepmimic_run");
    failure->set_frame(3);
    failure->set_terminated(true);
    failure->set_steps(5);
    auto state = client->ReportFailures(request);
    ASSERT_TRUE(state.ok()) << state.status();
    std::vector<float> zeros(2 * 69, 0.f);
    ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
    auto stats = client->GetStats();
    ASSERT_TRUE(stats.ok());
    ASSERT_EQ(stats->sessions_size(), 1);
    ASSERT_EQ(stats->sessions(0).clips_size(), 3);
    for (int c = 0; c < 3; ++c) {
      const double p = state->clips(c).probability();
      EXPECT_DOUBLE_EQ(stats->sessions(0).clips(c).probability(), p);
      if (scheme == SamplingScheme::kUniform) {
        EXPECT_DOUBLE_EQ(p, 1.0 / 3) << c;
        EXPECT_DOUBLE_EQ(state->clips(c).weight(), 1.0);
      }
    }
    if (scheme == SamplingScheme::kDecayOnSuccess) {
      EXPECT_DOUBLE_EQ(state->clips(1).weight(), 1.0);
      EXPECT_NEAR(state->clips(0).weight(), std::pow(0.999, 10), 1e-12);
      EXPECT_GT(state->clips(1).probability(), state->clips(0).probability());
    }
    if (scheme == SamplingScheme::kFailureRate) {  // one failure in 5 steps, on the prior's 1 in 30
      EXPECT_NEAR(state->clips(1).weight(), 2.0 / 35.0, 1e-12);
      EXPECT_GT(state->clips(1).probability(), 2 * state->clips(0).probability());
    }
    EXPECT_EQ(state->clips(1).failures(), 1);
    EXPECT_TRUE((*stream)->Close().ok());
    server->Shutdown(absl::Seconds(1));
  }
}

TEST_F(SimulationServerTest, StepResultsCarryPerPartErrors) {
  for (const std::string layout : {"5part", "3part"}) {
    const int n = 4;
    v1::SessionConfig config = Config(n, 2);
    config.set_part_layout(layout);
    auto stream = client_->OpenSession(config);
    ASSERT_TRUE(stream.ok()) << stream.status();
    const v1::EnvSpec& spec = (*stream)->spec();
    const int parts = spec.parts_size();
    const v1::Tensor& initial = (*stream)->opened().initial().part_error();
    ASSERT_EQ(initial.shape_size(), 2);
    EXPECT_EQ(initial.shape(0), n);
    EXPECT_EQ(initial.shape(1), parts);
    EXPECT_EQ(initial.dtype(), v1::FLOAT32);
    std::vector<float> errors;
    ASSERT_TRUE(ReadFloatTensor(initial, "part_error", &errors).ok());
    ASSERT_EQ(errors.size(), static_cast<size_t>(n) * parts);
    for (float e : errors) EXPECT_EQ(e, 0.f);  // reset onto the reference
    std::vector<float> zeros(static_cast<size_t>(n) * 69, 0.f), mean;
    for (int s = 0; s < 3; ++s) {
      ASSERT_TRUE((*stream)->Step(zeros.data()).ok());
      const v1::StepResult& result = (*stream)->result();
      ASSERT_EQ(result.part_error().shape(1), parts);
      ASSERT_TRUE(ReadFloatTensor(result.part_error(), "part_error", &errors).ok());
      ASSERT_TRUE(ReadFloatTensor(result.mean_body_error(), "mean_body_error", &mean).ok());
      for (int i = 0; i < n; ++i) {
        // Part means weighted by their body counts give the whole-body mean.
        double weighted = 0;
        for (int p = 0; p < parts; ++p) {
          const float e = errors[static_cast<size_t>(i) * parts + p];
          EXPECT_GT(e, 0.f) << layout << " step " << s << " env " << i << " part " << p;
          EXPECT_LT(e, 1.f);
          weighted += e * spec.parts(p).bodies_size();
        }
        EXPECT_NEAR(weighted / spec.body_names_size(), mean[i], 1e-5) << layout << " env " << i;
      }
    }
    EXPECT_TRUE((*stream)->Close().ok());
  }
}

TEST_F(SimulationServerTest, SampleReferenceAmpMatchesTheResetHistories) {
  v1::SessionConfig config = Config(2);
  config.add_motions("deepmimic_walk");
  auto stream = client_->OpenSession(config);
  ASSERT_TRUE(stream.ok());
  v1::SampleReferenceAmpRequest request;
  request.set_session_id((*stream)->opened().session_id());
  request.set_num_samples(50);
  request.set_seed(3);
  auto samples = client_->SampleReferenceAmp(request);
  ASSERT_TRUE(samples.ok()) << samples.status();
  ASSERT_EQ(samples->amp_obs().shape(0), 50);
  ASSERT_EQ(samples->amp_obs().shape(1), 2320);
  std::vector<float> values;
  ASSERT_TRUE(ReadFloatTensor(samples->amp_obs(), "amp_obs", &values).ok());
  // Each sample is a reference history: the initial AMP rows of the session are too, and the
  // root height (feature 0) of every frame lies in the walk clip's range.
  const MotionClip& walk = DefaultMotions()->clip(DefaultMotions()->Find("deepmimic_walk"));
  double low = 1e9, high = -1e9;
  for (int f = 0; f < walk.num_frames; ++f) {
    low = std::min(low, walk.body_pos[f * 24].z());
    high = std::max(high, walk.body_pos[f * 24].z());
  }
  for (int s = 0; s < 50; ++s) {
    for (int k = 0; k < 10; ++k) {
      const float height = values[s * 2320 + k * 232];
      EXPECT_GE(height, low - 1e-4);
      EXPECT_LE(height, high + 1e-4);
    }
  }
  request.set_num_samples(0);
  auto zero = client_->SampleReferenceAmp(request);
  ASSERT_FALSE(zero.ok());
  EXPECT_THAT(std::string(zero.status().message()), HasSubstr("num_samples"));
  request.set_num_samples(10);
  request.set_session_id("nope");
  EXPECT_EQ(client_->SampleReferenceAmp(request).status().code(), absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace modskill
