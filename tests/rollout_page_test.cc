// A rollout's viewer page end to end: the geometry the server describes is the compiled model's,
// the frames in the page equal the frames the server streamed (positions, rotations, errors,
// flags), and malformed geometry or frames are errors naming the field. The page in a browser:
// tests/viewer/.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "absl/strings/escaping.h"
#include "common/atomic_file.h"
#include "common/policy/family_parameters.h"
#include "common/policy/policy_checkpoint.h"
#include "common/viewer/viewer_html.h"
#include "common/viewer/viewer_wire.h"
#include "common/wire/tensor_codec.h"
#include "server/core/env/policy_fit.h"
#include "server/core/motion/clip_view.h"
#include "tests/server_fixture.h"
#include "tests/simulation_server_fixture.h"
#include "tests/viewer_page_reading.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

std::vector<float> TensorFloats(const v1::Tensor& tensor) {
  std::vector<float> values(tensor.data().size() / 4);
  std::memcpy(values.data(), tensor.data().data(), values.size() * 4);
  return values;
}

class RolloutPageTest : public SimulationServerTest {
 protected:
  void SetUp() override {
    SimulationServerTest::SetUp();
    // A stand-in for three.js, so that these tests need no libjs-three.
    fake_three_ = TempDir() + "/fake_three.min.js";
    std::ofstream(fake_three_) << "window.THREE = {};";
    setenv("MODSKILL_THREE_JS", fake_three_.c_str(), 1);
  }
  void TearDown() override {
    unsetenv("MODSKILL_THREE_JS");
    SimulationServerTest::TearDown();
  }

  std::string fake_three_;
};

TEST_F(RolloutPageTest, DescribedGeometryIsTheCompiledModels) {
  auto spec = client_->Describe();
  ASSERT_TRUE(spec.ok()) << spec.status();
  auto bodies = ViewerBodiesFromWire(*spec);
  ASSERT_TRUE(bodies.ok()) << bodies.status();
  const std::vector<ViewerBody> expected = ViewerBodiesFromSpec(DefaultSpec());
  ASSERT_EQ(bodies->size(), expected.size());
  for (size_t b = 0; b < expected.size(); ++b) {
    const ViewerBody& got = (*bodies)[b];
    EXPECT_EQ(got.name, expected[b].name);
    EXPECT_EQ(got.parent, expected[b].parent);
    EXPECT_EQ(got.geom.type, expected[b].geom.type) << got.name;
    EXPECT_NEAR(got.geom.radius, expected[b].geom.radius, 1e-6) << got.name;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(got.geom.from[k], expected[b].geom.from[k], 1e-6) << got.name;
      EXPECT_NEAR(got.geom.to[k], expected[b].geom.to[k], 1e-6) << got.name;
      EXPECT_NEAR(got.geom.center[k], expected[b].geom.center[k], 1e-6) << got.name;
      EXPECT_NEAR(got.geom.half_extents[k], expected[b].geom.half_extents[k], 1e-6) << got.name;
    }
  }
}

// The page's arrays for one clip equal its streamed frames, value for value; the streamed error
// is the mean distance of the streamed positions; rotations are unit quaternions.
void ExpectPageClipEqualsFrames(const nlohmann::json& clip, const std::vector<v1::RolloutFrame>& frames) {
  const std::string name = clip["name"];
  const std::vector<float> ref_pos = DecodeFloats(clip["tracks"][0]["pos"]);
  const std::vector<float> ref_rot = DecodeFloats(clip["tracks"][0]["rot"]);
  const std::vector<float> sim_pos = DecodeFloats(clip["tracks"][1]["pos"]);
  const std::vector<float> sim_rot = DecodeFloats(clip["tracks"][1]["rot"]);
  const std::vector<float> error = DecodeFloats(clip["body_error"]);
  std::string flags;
  ASSERT_TRUE(absl::Base64Unescape(clip["flags"].get<std::string>(), &flags));
  ASSERT_EQ(flags.size(), frames.size());
  for (size_t f = 0; f < frames.size(); ++f) {
    const std::pair<const std::vector<float>*, const v1::Tensor*> pairs[4] = {
        {&ref_pos, &frames[f].ref_body_pos()}, {&ref_rot, &frames[f].ref_body_rot()},
        {&sim_pos, &frames[f].sim_body_pos()}, {&sim_rot, &frames[f].sim_body_rot()}};
    for (const auto& [page_values, tensor] : pairs) {
      const std::vector<float> wire = TensorFloats(*tensor);
      ASSERT_EQ(page_values->size(), wire.size() * frames.size());
      for (size_t i = 0; i < wire.size(); ++i) {
        ASSERT_EQ((*page_values)[f * wire.size() + i], wire[i]) << name << " frame " << f;
      }
    }
    EXPECT_EQ(error[f], frames[f].mean_body_error_m());
    const bool last = f + 1 == frames.size();
    EXPECT_EQ(frames[f].done(), last) << name << " frame " << f;
    EXPECT_EQ((flags[f] & kViewerDone) != 0, last);
    EXPECT_EQ((flags[f] & kViewerTerminated) != 0, frames[f].terminated());
  }
  // The streamed error is the mean distance of the streamed positions.
  const std::vector<float> sim = TensorFloats(frames.back().sim_body_pos());
  const std::vector<float> ref = TensorFloats(frames.back().ref_body_pos());
  double mean = 0;
  for (size_t b = 0; b < sim.size() / 3; ++b) {
    mean += std::hypot(sim[3 * b] - ref[3 * b], sim[3 * b + 1] - ref[3 * b + 1], sim[3 * b + 2] - ref[3 * b + 2]);
  }
  EXPECT_NEAR(mean / (sim.size() / 3), frames.back().mean_body_error_m(), 1e-4);
  // A unit quaternion per body.
  for (size_t q = 0; q + 3 < sim_rot.size(); q += 4) {
    const double norm = std::sqrt(sim_rot[q] * sim_rot[q] + sim_rot[q + 1] * sim_rot[q + 1] +
                                  sim_rot[q + 2] * sim_rot[q + 2] + sim_rot[q + 3] * sim_rot[q + 3]);
    ASSERT_NEAR(norm, 1.0, 1e-4);
  }
}

TEST_F(RolloutPageTest, PageFramesEqualTheStreamedFrames) {
  auto spec = client_->Describe();
  auto motions = client_->ListMotions();
  ASSERT_TRUE(spec.ok() && motions.ok());
  auto page = PrepareRolloutPage(*spec, *motions);
  ASSERT_TRUE(page.ok()) << page.status();
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(OpenLoopPolicyBytes());
  request.add_clips("deepmimic_walk");
  request.add_clips("deepmimic_run");
  request.set_stream_frames(true);
  std::map<std::string, std::vector<v1::RolloutFrame>> streamed;
  auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame& frame) {
    streamed[frame.clip()].push_back(frame);
    page->Add(frame);
  });
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  ASSERT_TRUE(page->error().ok()) << page->error();

  auto scene = page->TakeScene("open loop");
  ASSERT_TRUE(scene.ok()) << scene.status();
  const std::string path = TempDir() + "/rollout_page.html";
  ASSERT_TRUE(WriteViewerHtml(path, *scene).ok());
  auto html = ReadFileToString(path, 64 << 20);
  ASSERT_TRUE(html.ok());
  const nlohmann::json json = PageScene(*html);
  EXPECT_EQ(json["bodies"].size(), 24u);
  ASSERT_EQ(json["clips"].size(), 2u);
  for (const nlohmann::json& clip : json["clips"]) {
    const std::string name = clip["name"];
    const std::vector<v1::RolloutFrame>& frames = streamed[name];
    ASSERT_EQ(clip["frames"].get<size_t>(), frames.size()) << name;
    EXPECT_NEAR(clip["fps"].get<double>(), 1.0 / spec->control_dt(), 1e-9);
    EXPECT_FALSE(clip["label"].get<std::string>().empty()) << name;
    // One frame per simulated step plus the first (the clip's metrics count steps).
    for (const v1::ClipMetrics& m : *metrics) {
      if (m.clip() == name) EXPECT_EQ(static_cast<size_t>(m.steps() + 1), frames.size());
    }
    ASSERT_EQ(clip["tracks"].size(), 2u);
    EXPECT_EQ(clip["tracks"][0]["role"], "reference");
    EXPECT_EQ(clip["tracks"][1]["role"], "simulated");
    ExpectPageClipEqualsFrames(clip, frames);
  }
  // Both clips ran from their first frame.
  EXPECT_EQ(streamed["deepmimic_walk"].front().frame(), 0);
  EXPECT_EQ(streamed["deepmimic_run"].front().frame(), 0);
}

// A family at other body proportions (a zero affine family policy over leg_scale, run at 1.2): the
// page draws the legs stretched as the server stretched them, every other body as described.
TEST_F(RolloutPageTest, FamilyLimbsAreDrawnAtTheirScale) {
  auto spec = client_->Describe();
  auto motions = client_->ListMotions();
  ASSERT_TRUE(spec.ok() && motions.ok());
  PolicySpec family;
  family.part_layout = spec->part_layout();
  family.obs_size = spec->obs_size() + 2;  // a normalized, then the phase
  family.action_size = spec->action_size() + 1;  // the time warp
  family.joint_names.assign(spec->joint_names().begin(), spec->joint_names().end());
  family.control_dt = spec->control_dt();
  family.action.mode = ActionMode::kResidual;
  family.family_clip = "deepmimic_walk";
  family.family_frames = motions->motions(0).frames();
  for (const v1::MotionInfo& info : motions->motions()) {
    if (info.name() == "deepmimic_walk") family.family_frames = info.frames();
  }
  family.family = {{"leg_scale", 0.8, 1.2}};
  auto bytes = AffinePolicyBytes(family, {}, {});
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  auto page = PrepareRolloutPage(*spec, *motions);
  ASSERT_TRUE(page.ok()) << page.status();
  v1::RolloutRequest request;
  request.set_checkpoint_bytes(*bytes);
  request.set_stream_frames(true);
  (*request.mutable_family_params())["leg_scale"] = 1.2;
  auto metrics = client_->Rollout(request, [&](const v1::RolloutFrame& frame) { page->Add(frame); });
  ASSERT_TRUE(metrics.ok()) << metrics.status();
  ASSERT_EQ(metrics->size(), 1u);
  EXPECT_EQ(metrics->front().family().params().at("leg_scale"), 1.2);
  page->ScaleFamilyLimbs(1.2, 1.0);
  auto scene = page->TakeScene("family");
  ASSERT_TRUE(scene.ok()) << scene.status();
  auto described = ViewerBodiesFromWire(*spec);
  ASSERT_TRUE(described.ok());
  for (size_t b = 0; b < scene->bodies.size(); ++b) {
    const ViewerBody& drawn = scene->bodies[b];
    const double expected = FamilyLimbScale(drawn.name, 1.2, 1.0);
    EXPECT_NEAR(drawn.geom.radius, expected * (*described)[b].geom.radius, 1e-12) << drawn.name;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(drawn.geom.to[k], expected * (*described)[b].geom.to[k], 1e-12) << drawn.name;
  }
  EXPECT_EQ(FamilyLimbScale("L_Knee", 1.2, 1.0), 1.2);
  EXPECT_EQ(FamilyLimbScale("R_Elbow", 1.2, 0.9), 0.9);
  EXPECT_EQ(FamilyLimbScale("Torso", 1.2, 0.9), 1.0);
}

TEST_F(RolloutPageTest, MalformedGeometryAndFramesAreErrorsNamingTheField) {
  auto spec = client_->Describe();
  ASSERT_TRUE(spec.ok());
  // A server without geometry (older than the viewer).
  v1::EnvSpec bare = *spec;
  bare.clear_body_geometry();
  auto none = RolloutViewerRecorder::ForSpec(bare);
  ASSERT_FALSE(none.ok());
  EXPECT_EQ(none.status().code(), absl::StatusCode::kFailedPrecondition);
  EXPECT_THAT(std::string(none.status().message()), HasSubstr("body_geometry"));
  // A parent that is not an earlier body, a 2-vector, an unknown shape, a NaN radius.
  const auto expect_data_loss = [](const v1::EnvSpec& bad, const std::string& needle) {
    auto result = RolloutViewerRecorder::ForSpec(bad);
    ASSERT_FALSE(result.ok()) << needle;
    EXPECT_EQ(result.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_THAT(std::string(result.status().message()), HasSubstr(needle));
  };
  v1::EnvSpec bad = *spec;
  bad.mutable_body_geometry(3)->set_parent(3);
  expect_data_loss(bad, "body_geometry[3]");
  bad = *spec;
  bad.mutable_body_geometry(2)->mutable_center()->RemoveLast();
  expect_data_loss(bad, "center");
  bad = *spec;
  bad.mutable_body_geometry(1)->set_shape(static_cast<v1::BodyGeometry::Shape>(9));
  expect_data_loss(bad, "shape");
  bad = *spec;
  bad.mutable_body_geometry(0)->set_radius(std::nanf(""));
  expect_data_loss(bad, "radius");
  bad = *spec;
  bad.mutable_body_geometry()->RemoveLast();
  expect_data_loss(bad, "23 entries for 24 body_names");

  auto recorder = RolloutViewerRecorder::ForSpec(*spec);
  ASSERT_TRUE(recorder.ok()) << recorder.status();
  auto empty = recorder->TakeScene("nothing");
  ASSERT_FALSE(empty.ok());
  EXPECT_THAT(std::string(empty.status().message()), HasSubstr("no frames"));
  // A frame whose rotations have the width of positions: the error names the field and sticks.
  v1::RolloutFrame frame;
  frame.set_clip("deepmimic_walk");
  std::vector<float> zeros(24 * 4, 0.0f);
  SetFloatTensor({24, 3}, zeros.data(), frame.mutable_sim_body_pos());
  SetFloatTensor({24, 3}, zeros.data(), frame.mutable_ref_body_pos());
  SetFloatTensor({24, 4}, zeros.data(), frame.mutable_ref_body_rot());
  SetFloatTensor({24, 3}, zeros.data(), frame.mutable_sim_body_rot());
  recorder->Add(frame);
  EXPECT_EQ(recorder->error().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(std::string(recorder->error().message()), HasSubstr("RolloutFrame.sim_body_rot"));
  SetFloatTensor({24, 4}, zeros.data(), frame.mutable_sim_body_rot());
  recorder->Add(frame);  // good, but after a bad one
  EXPECT_EQ(recorder->num_frames(), 0);
  EXPECT_FALSE(recorder->TakeScene("bad").ok());
}

}  // namespace
}  // namespace modskill
