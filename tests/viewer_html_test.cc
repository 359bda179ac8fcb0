// The HTML viewer's writer: the frames in the page equal the clip's body poses, the geometry
// equals the compiled MuJoCo model's, and bad input (no frames, an unwritable path, no three.js)
// is a clear error that leaves no file. The page in a browser: tests/viewer/.
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "absl/strings/escaping.h"
#include "common/atomic_file.h"
#include "common/viewer/viewer_html.h"
#include "server/core/motion/clip_view.h"
#include "server/core/motion/motion_library.h"
#include "server/core/sim/humanoid_model.h"
#include "tests/test_files.h"
#include "tests/viewer_page_reading.h"

namespace modskill {
namespace {

using ::testing::HasSubstr;

class ViewerHtmlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ProcessTempDir("viewer_html_test");
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    // A stand-in for three.js, so that these tests need no libjs-three.
    fake_three_ = dir_ + "/three.min.js";
    std::ofstream(fake_three_) << "window.THREE = {};";
    setenv("MODSKILL_THREE_JS", fake_three_.c_str(), 1);
    auto spec = HumanoidSpec::LoadDefault();
    ASSERT_TRUE(spec.ok()) << spec.status();
    spec_ = *spec;
    auto library = MotionLibrary::LoadDefault(spec_);
    ASSERT_TRUE(library.ok()) << library.status();
    const int walk = library->Find("deepmimic_walk");
    ASSERT_GE(walk, 0);
    clip_ = library->clip(walk);
  }
  void TearDown() override { unsetenv("MODSKILL_THREE_JS"); }

  ViewerScene WalkScene() {
    ViewerScene scene;
    scene.title = "walk";
    scene.bodies = ViewerBodiesFromSpec(spec_);
    auto view = ViewerClipFromMotion(clip_);
    EXPECT_TRUE(view.ok()) << view.status();
    scene.clips.push_back(*view);
    return scene;
  }

  std::string dir_, fake_three_;
  HumanoidSpec spec_;
  MotionClip clip_;
};

TEST_F(ViewerHtmlTest, PageFramesEqualTheClipsBodyPoses) {
  const std::string path = dir_ + "/walk.html";
  ASSERT_TRUE(WriteViewerHtml(path, WalkScene()).ok());
  auto html = ReadFileToString(path, 64 << 20);
  ASSERT_TRUE(html.ok());
  EXPECT_THAT(*html, HasSubstr("window.THREE = {};"));
  const nlohmann::json scene = PageScene(*html);
  ASSERT_EQ(scene["clips"].size(), 1u);
  const nlohmann::json& clip = scene["clips"][0];
  EXPECT_EQ(clip["name"], "deepmimic_walk");
  ASSERT_EQ(clip["frames"].get<int>(), clip_.num_frames);
  const std::vector<float> pos = DecodeFloats(clip["tracks"][0]["pos"]);
  const std::vector<float> rot = DecodeFloats(clip["tracks"][0]["rot"]);
  const size_t poses = static_cast<size_t>(clip_.num_frames) * clip_.num_bodies;
  ASSERT_EQ(pos.size(), 3 * poses);
  ASSERT_EQ(rot.size(), 4 * poses);
  for (size_t i = 0; i < poses; ++i) {
    for (int k = 0; k < 3; ++k) ASSERT_NEAR(pos[3 * i + k], clip_.body_pos[i][k], 1e-6) << "pose " << i;
    const Quat& q = clip_.body_rot[i];
    const double expected[4] = {q.w(), q.x(), q.y(), q.z()};
    for (int k = 0; k < 4; ++k) ASSERT_NEAR(rot[4 * i + k], expected[k], 1e-6) << "pose " << i;
  }
  EXPECT_TRUE(clip["body_error"].is_null());
}

TEST_F(ViewerHtmlTest, GeometryIsTheCompiledModels) {
  auto model = HumanoidModel::Create(spec_, PhysicsOptions());
  ASSERT_TRUE(model.ok()) << model.status();
  const mjModel* m = (*model)->model();
  const std::vector<ViewerBody> bodies = ViewerBodiesFromSpec(spec_);
  ASSERT_EQ(static_cast<int>(bodies.size()), m->nbody - 1);
  for (size_t i = 0; i < bodies.size(); ++i) {
    const int body = (*model)->mj_body_id(static_cast<int>(i));
    ASSERT_EQ(m->body_geomnum[body], 1) << bodies[i].name;
    const int g = m->body_geomadr[body];
    const ViewerGeom& geom = bodies[i].geom;
    const mjtNum* size = m->geom_size + 3 * g;
    const mjtNum* pos = m->geom_pos + 3 * g;
    switch (geom.type) {
      case ViewerGeom::Type::kSphere:
        EXPECT_EQ(m->geom_type[g], mjGEOM_SPHERE) << bodies[i].name;
        EXPECT_NEAR(size[0], geom.radius, 1e-5);
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(pos[k], geom.center[k], 1e-5);
        break;
      case ViewerGeom::Type::kCapsule: {
        EXPECT_EQ(m->geom_type[g], mjGEOM_CAPSULE) << bodies[i].name;
        EXPECT_NEAR(size[0], geom.radius, 1e-5);
        double length2 = 0;
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(pos[k], 0.5 * (geom.from[k] + geom.to[k]), 1e-5) << bodies[i].name;
          length2 += (geom.to[k] - geom.from[k]) * (geom.to[k] - geom.from[k]);
        }
        EXPECT_NEAR(size[1], 0.5 * std::sqrt(length2), 1e-5) << bodies[i].name;
        break;
      }
      case ViewerGeom::Type::kBox:
        EXPECT_EQ(m->geom_type[g], mjGEOM_BOX) << bodies[i].name;
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(size[k], geom.half_extents[k], 1e-5) << bodies[i].name;
          EXPECT_NEAR(pos[k], geom.center[k], 1e-5) << bodies[i].name;
        }
        break;
    }
  }
}

TEST_F(ViewerHtmlTest, ZeroFramesIsAnErrorNamingTheClipAndWritesNothing) {
  MotionClip empty = clip_;
  empty.name = "empty_clip";
  empty.num_frames = 0;
  auto view = ViewerClipFromMotion(empty);
  ASSERT_FALSE(view.ok());
  EXPECT_THAT(std::string(view.status().message()), HasSubstr("empty_clip"));

  ViewerScene scene = WalkScene();
  scene.clips[0].name = "no_frames";
  scene.clips[0].num_frames = 0;
  const std::string path = dir_ + "/empty.html";
  const absl::Status status = WriteViewerHtml(path, scene);
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(std::string(status.message()), HasSubstr("no_frames"));
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST_F(ViewerHtmlTest, InconsistentSizesAndNonFiniteNumbersAreErrors) {
  ViewerScene scene = WalkScene();
  scene.clips[0].tracks[0].pos.pop_back();
  EXPECT_THAT(std::string(ValidateViewerScene(scene).message()), HasSubstr("deepmimic_walk"));
  scene = WalkScene();
  scene.clips[0].tracks[0].rot[5] = std::nanf("");
  EXPECT_FALSE(ValidateViewerScene(scene).ok());
  scene = WalkScene();
  scene.clips[0].body_error = {0.1f};
  EXPECT_THAT(std::string(ValidateViewerScene(scene).message()), HasSubstr("body_error"));
  scene = WalkScene();
  scene.clips.clear();
  EXPECT_FALSE(ValidateViewerScene(scene).ok());
}

TEST_F(ViewerHtmlTest, UnwritablePathIsAnErrorNamingItAndLeavesNoPartialFile) {
  const std::string path = dir_ + "/no_such_dir/page.html";
  const absl::Status status = WriteViewerHtml(path, WalkScene());
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(std::string(status.message()), HasSubstr(path));
  EXPECT_FALSE(std::filesystem::exists(dir_ + "/no_such_dir"));
  // A failed write over an existing page keeps the old page whole.
  const std::string existing = dir_ + "/existing.html";
  std::ofstream(existing) << "old page";
  ViewerScene bad = WalkScene();
  bad.clips[0].num_frames = 0;
  EXPECT_FALSE(WriteViewerHtml(existing, bad).ok());
  EXPECT_EQ(*ReadFileToString(existing, 1024), "old page");
  for (const auto& entry : std::filesystem::directory_iterator(dir_)) {
    EXPECT_THAT(entry.path().filename().string(), ::testing::Not(HasSubstr(".tmp.")));
  }
}

TEST_F(ViewerHtmlTest, MissingThreeJsIsAnErrorNamingThePathAndThePackage) {
  const std::string missing = dir_ + "/missing/three.min.js";
  setenv("MODSKILL_THREE_JS", missing.c_str(), 1);
  const std::string path = dir_ + "/page.html";
  const absl::Status status = WriteViewerHtml(path, WalkScene());
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(std::string(status.message()), HasSubstr(missing));
  EXPECT_THAT(std::string(status.message()), HasSubstr("libjs-three"));
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST_F(ViewerHtmlTest, NamesCannotCloseTheScriptElement) {
  ViewerScene scene = WalkScene();
  scene.title = "</title><script>alert(1)</script>";
  scene.clips[0].label = "</script><script>alert(2)</script>";
  auto html = RenderViewerHtml(scene, "/* three */");
  ASSERT_TRUE(html.ok());
  EXPECT_EQ(html->find("<script>alert"), std::string::npos);
  EXPECT_EQ(PageScene(*html)["clips"][0]["label"], scene.clips[0].label);
}

}  // namespace
}  // namespace modskill
