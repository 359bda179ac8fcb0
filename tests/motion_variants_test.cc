// The built-in variant generator (motion displacement mapping + time warping) and the
// plausibility filter, on the shipped clips.
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "server/core/curriculum/motion_variants.h"
#include "server/core/curriculum/plausibility_filter.h"
#include "server/core/sim/part_layout.h"
#include "tests/test_fixtures.h"

namespace modskill {
namespace {

const PartLayout& FivePartLayout() {
  static const PartLayout* layout = [] {
    auto catalog = PartLayoutCatalog::LoadDefault(DefaultSpec());
    EXPECT_TRUE(catalog.ok()) << catalog.status();
    auto five = catalog->Get("5part");
    EXPECT_TRUE(five.ok()) << five.status();
    return new PartLayout(*five);
  }();
  return *layout;
}

bool SameQuat(const Quat& a, const Quat& b) { return a.coeffs() == b.coeffs(); }

std::vector<MotionVariant> Generate(const MotionClip& parent, const VariantOptions& options) {
  auto variants = GenerateVariants(DefaultSpec(), FivePartLayout(), parent, options);
  EXPECT_TRUE(variants.ok()) << variants.status();
  return variants.ok() ? *std::move(variants) : std::vector<MotionVariant>();
}

// The shipped clips are not quite inside the skeleton's hinge ranges, so the filter's joint-limit
// check is loosened when they (or part-level variants, which keep the parent's other parts) are
// judged: the retargeted knees carry up to 8 deg of ab/adduction, 0.14 rad over PHC's +-5.6 deg.
// The check itself is tested on planted and whole-body variants with the defaults.
PlausibilityOptions ShippedClipOptions() {
  PlausibilityOptions options;
  options.max_limit_violation = 0.15;
  return options;
}

// True when the knee can bend (its flexion hinge, _x, turns about y in the z-up frame).
// A knee clamped straight makes every walk variant that displaces a leg drag its swinging foot.
bool KneeCanFlex() {
  const BodySpec& knee = DefaultSpec().body(DefaultSpec().BodyIndex("L_Knee"));
  return knee.range_high[0] - knee.range_low[0] > 1.0;
}

// cmu_02_01 starts with a calibration pose: its hands jump 23 m/s into frame 1. The clip from
// frame 1 on is the walk itself.
MotionClip WithoutFirstFrame(const MotionClip& clip) {
  MotionClip trimmed = clip;
  trimmed.num_frames = clip.num_frames - 1;
  trimmed.root_pos.erase(trimmed.root_pos.begin());
  trimmed.local_rot.erase(trimmed.local_rot.begin(), trimmed.local_rot.begin() + clip.num_bodies);
  EXPECT_TRUE(ComputeClipKinematics(DefaultSpec(), &trimmed).ok());
  return trimmed;
}

double MaxRotationDifference(const MotionClip& a, const MotionClip& b, const std::vector<int>& bodies) {
  double largest = 0;
  for (int f = 0; f < std::min(a.num_frames, b.num_frames); ++f) {
    for (int body : bodies) largest = std::max(largest, a.local(f, body).angularDistance(b.local(f, body)));
  }
  return largest;
}

TEST(MotionVariantsTest, PartVariantsLeaveEveryOtherPartBitIdentical) {
  const PartLayout& layout = FivePartLayout();
  for (const std::string name : {"deepmimic_walk", "cmu_02_01"}) {
    const MotionClip& parent = ShippedClip(name);
    for (int part = 0; part < layout.num_parts(); ++part) {
      SCOPED_TRACE(name + " part " + layout.parts[part].name);
      VariantOptions options;
      options.part = part;
      options.count = 2;
      options.seed = 11;
      const std::vector<MotionVariant> variants = Generate(parent, options);
      ASSERT_EQ(variants.size(), 2u);
      std::vector<bool> in_part(parent.num_bodies, false);
      for (int body : layout.parts[part].bodies) in_part[body] = true;
      for (size_t k = 0; k < variants.size(); ++k) {
        const MotionClip& clip = variants[k].clip;
        ASSERT_EQ(clip.num_frames, parent.num_frames);
        EXPECT_EQ(clip.fps, parent.fps);
        for (int f = 0; f < clip.num_frames; ++f) {
          for (int b = 0; b < clip.num_bodies; ++b) {
            if (in_part[b]) continue;
            ASSERT_TRUE(SameQuat(clip.local(f, b), parent.local(f, b))) << "frame " << f << " body " << b;
          }
        }
        EXPECT_GT(MaxRotationDifference(clip, parent, layout.parts[part].bodies), 0.05);
        // Arms and torso move no foot, so the root (shared, owned by no part) stays the parent's,
        // the pelvis of the torso part included.
        const std::string& part_name = layout.parts[part].name;
        if (part_name != "L_Leg" && part_name != "R_Leg") {
          EXPECT_TRUE(clip.root_pos == parent.root_pos);
          for (int f = 0; f < clip.num_frames; ++f) EXPECT_TRUE(SameQuat(clip.local(f, 0), parent.local(f, 0)));
        }
        EXPECT_EQ(clip.name, name + "~" + part_name + "~" + std::to_string(k));
        EXPECT_EQ(clip.label, parent.label);
        EXPECT_EQ(clip.source, "generated from " + name + " by builtin_displacement (part " + part_name + ", seed 11)");
        EXPECT_EQ(variants[k].provenance.parent, name);
        EXPECT_EQ(variants[k].provenance.generator, kBuiltinVariantGenerator);
        EXPECT_EQ(variants[k].provenance.part, part);
        EXPECT_EQ(variants[k].provenance.seed, 11u);
        EXPECT_EQ(clip.body_pos.size(), static_cast<size_t>(clip.num_frames * clip.num_bodies));
        EXPECT_EQ(clip.dof_pos.size(), static_cast<size_t>(clip.num_frames * clip.num_hinges()));
      }
    }
  }
}

TEST(MotionVariantsTest, WholeBodyVariantsAreDeterministicPerSeedAndWarpWithinBounds) {
  const MotionClip& parent = ShippedClip("deepmimic_walk");
  auto identical = [](const MotionClip& a, const MotionClip& b) {
    if (a.num_frames != b.num_frames || !(a.root_pos == b.root_pos)) return false;
    for (size_t i = 0; i < a.local_rot.size(); ++i) {
      if (!SameQuat(a.local_rot[i], b.local_rot[i])) return false;
    }
    return true;
  };
  VariantOptions options;
  options.seed = 3;
  const std::vector<MotionVariant> first = Generate(parent, options);
  const std::vector<MotionVariant> again = Generate(parent, options);
  options.seed = 4;
  const std::vector<MotionVariant> other = Generate(parent, options);
  ASSERT_EQ(first.size(), 3u);
  ASSERT_EQ(again.size(), 3u);
  ASSERT_EQ(other.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(identical(first[k].clip, again[k].clip)) << k;
    EXPECT_FALSE(identical(first[k].clip, other[k].clip)) << k;
    EXPECT_EQ(first[k].clip.name, "deepmimic_walk~w~" + std::to_string(k));
    EXPECT_EQ(first[k].provenance.part, -1);
  }
  EXPECT_FALSE(identical(first[0].clip, first[1].clip));

  for (double amplitude : {0.25, 0.6}) {
    options.time_warp_amplitude = amplitude;
    options.count = 8;
    bool some_warp = false;
    for (const MotionVariant& variant : Generate(parent, options)) {
      const double ratio = variant.clip.duration() / parent.duration();
      EXPECT_GE(ratio, 1.0 / (1.0 + amplitude) - 1e-9) << variant.clip.name;
      EXPECT_LE(ratio, 1.0 / (1.0 - amplitude) + 1e-9) << variant.clip.name;
      EXPECT_EQ(variant.clip.fps, parent.fps);
      some_warp = some_warp || variant.clip.num_frames != parent.num_frames;
    }
    EXPECT_TRUE(some_warp) << amplitude;
  }
}

TEST(MotionVariantsTest, GeneratedHingeAnglesStayWithinRanges) {
  const HumanoidSpec& spec = DefaultSpec();
  const PartLayout& layout = FivePartLayout();
  auto expect_within = [&](const MotionClip& clip, const std::vector<bool>& checked) {
    const int hinges = clip.num_hinges();
    for (int f = 0; f < clip.num_frames; ++f) {
      for (int h = 0; h < hinges; ++h) {
        const int body = 1 + h / 3;
        if (!checked[body]) continue;
        const double angle = clip.dof_pos[f * hinges + h];
        ASSERT_GE(angle, spec.body(body).range_low[h % 3] - 1e-6) << clip.name << " frame " << f << " hinge " << h;
        ASSERT_LE(angle, spec.body(body).range_high[h % 3] + 1e-6) << clip.name << " frame " << f << " hinge " << h;
      }
    }
  };
  // deepmimic_run bends the knees past 90 degrees, where the x-y-z decomposition flips.
  for (const std::string name : {"deepmimic_walk", "cmu_02_01", "deepmimic_run"}) {
    const MotionClip& parent = ShippedClip(name);
    VariantOptions options;
    options.rotation_amplitude = 1.0;
    for (const MotionVariant& variant : Generate(parent, options)) {
      expect_within(variant.clip, std::vector<bool>(spec.num_bodies(), true));
    }
    // Part-level variants: the part's hinges; the others are the parent's, bit for bit (above).
    for (int part = 0; part < layout.num_parts(); ++part) {
      options.part = part;
      options.count = 1;
      std::vector<bool> in_part(spec.num_bodies(), false);
      for (int body : layout.parts[part].bodies) in_part[body] = true;
      for (const MotionVariant& variant : Generate(parent, options)) expect_within(variant.clip, in_part);
    }
  }
}

TEST(MotionVariantsTest, LegVariantsFollowTheParentsLowestPoint) {
  const HumanoidSpec& spec = DefaultSpec();
  const PartLayout& layout = FivePartLayout();
  for (const std::string name : {"deepmimic_walk", "cmu_02_01"}) {
    const MotionClip& parent = ShippedClip(name);
    // Without a warp, frame f of a variant is frame f of the parent.
    std::vector<VariantOptions> requests(3);
    requests[0].time_warp_amplitude = 0;
    for (int part = 0; part < layout.num_parts(); ++part) {
      if (layout.parts[part].name == "L_Leg") requests[1].part = part;
      if (layout.parts[part].name == "R_Leg") requests[2].part = part;
    }
    for (const VariantOptions& options : requests) {
      for (const MotionVariant& variant : Generate(parent, options)) {
        ASSERT_EQ(variant.clip.num_frames, parent.num_frames);
        for (int f = 0; f < parent.num_frames; ++f) {
          ASSERT_NEAR(LowestGeomPoint(spec, variant.clip, f), LowestGeomPoint(spec, parent, f), 0.02)
              << variant.clip.name << " frame " << f;
        }
      }
    }
  }
}

TEST(PlausibilityFilterTest, AcceptsTheShippedWalks) {
  const HumanoidSpec& spec = DefaultSpec();
  for (const MotionClip& clip : {ShippedClip("deepmimic_walk"), WithoutFirstFrame(ShippedClip("cmu_02_01"))}) {
    const PlausibilityVerdict verdict = CheckPlausibility(spec, clip, ShippedClipOptions());
    EXPECT_TRUE(verdict.accepted) << clip.name << ": " << verdict.reason;
    EXPECT_EQ(verdict.reason, "");
  }
  // A clip without kinematics is judged on its own computed kinematics.
  MotionClip bare = ShippedClip("deepmimic_walk");
  bare.body_pos.clear();
  bare.dof_pos.clear();
  EXPECT_TRUE(CheckPlausibility(spec, bare, ShippedClipOptions()).accepted);
}

TEST(PlausibilityFilterTest, AcceptsArmAndTorsoVariantsOfTheWalk) {
  const PartLayout& layout = FivePartLayout();
  for (int part = 0; part < layout.num_parts(); ++part) {
    const std::string& name = layout.parts[part].name;
    if (name == "L_Leg" || name == "R_Leg") continue;
    VariantOptions options;
    options.part = part;
    for (const MotionVariant& variant : Generate(ShippedClip("deepmimic_walk"), options)) {
      const PlausibilityVerdict verdict = CheckPlausibility(DefaultSpec(), variant.clip, ShippedClipOptions());
      EXPECT_TRUE(verdict.accepted) << variant.clip.name << ": " << verdict.reason;
    }
  }
}

TEST(PlausibilityFilterTest, AcceptsWholeBodyAndLegVariantsOfTheWalk) {
  if (!KneeCanFlex()) {
    GTEST_SKIP() << "the skeleton limits knee flexion to +-5.6 deg (PHC's y-up hinge ranges on the z-up axes), "
                    "so a displaced leg is clamped straight and drags its swinging foot";
  }
  const PartLayout& layout = FivePartLayout();
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  // Whole-body variants displace (and clamp) every joint: the default options apply as they are.
  for (const MotionVariant& variant : Generate(walk, VariantOptions())) {
    const PlausibilityVerdict verdict = CheckPlausibility(DefaultSpec(), variant.clip, PlausibilityOptions());
    EXPECT_TRUE(verdict.accepted) << variant.clip.name << ": " << verdict.reason;
  }
  for (int part = 0; part < layout.num_parts(); ++part) {
    const std::string& name = layout.parts[part].name;
    if (name != "L_Leg" && name != "R_Leg") continue;
    VariantOptions options;
    options.part = part;
    for (const MotionVariant& variant : Generate(walk, options)) {
      const PlausibilityVerdict verdict = CheckPlausibility(DefaultSpec(), variant.clip, ShippedClipOptions());
      EXPECT_TRUE(verdict.accepted) << variant.clip.name << ": " << verdict.reason;
    }
  }
}

TEST(PlausibilityFilterTest, RejectsPlantedDefectsNamingTheCheck) {
  const HumanoidSpec& spec = DefaultSpec();
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  auto verdict_after = [&](const std::function<void(MotionClip*)>& plant) {
    MotionClip clip = walk;
    plant(&clip);
    EXPECT_TRUE(ComputeClipKinematics(spec, &clip).ok());
    return CheckPlausibility(spec, clip, ShippedClipOptions());
  };

  // A knee bent 2.5 rad about its narrowest hinge (y in today's skeleton; the x-y-z decomposition
  // may report it on another hinge of the knee).
  const int knee = spec.BodyIndex("L_Knee");
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (spec.body(knee).range_high[a] - spec.body(knee).range_low[a] <
        spec.body(knee).range_high[axis] - spec.body(knee).range_low[axis]) {
      axis = a;
    }
  }
  PlausibilityVerdict verdict = verdict_after([&](MotionClip* clip) {
    Vec3 angles = Vec3::Zero();
    angles[axis] = 2.5;
    const Quat bent = HingeRotation(angles[0], angles[1], angles[2]);
    for (int f = 0; f < clip->num_frames; ++f) clip->local(f, knee) = bent;
  });
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(verdict.reason.rfind("joint_limit: L_Knee_", 0), 0u) << verdict.reason;
  EXPECT_NE(verdict.reason.find("frame"), std::string::npos) << verdict.reason;

  verdict = verdict_after([](MotionClip* clip) {
    for (Vec3& p : clip->root_pos) p.z() -= 0.2;
  });
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(verdict.reason.rfind("penetration: ", 0), 0u) << verdict.reason;
  EXPECT_NE(verdict.reason.find("frame"), std::string::npos) << verdict.reason;

  // Sideways drift at 2 m/s: every planted foot slides at 2 m/s.
  verdict = verdict_after([](MotionClip* clip) {
    for (int f = 0; f < clip->num_frames; ++f) clip->root_pos[f].y() += 2.0 * f / clip->fps;
  });
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(verdict.reason.rfind("foot_skate: ", 0), 0u) << verdict.reason;
  EXPECT_NE(verdict.reason.find("frame"), std::string::npos) << verdict.reason;

  // The root teleports 1 m for one frame.
  verdict = verdict_after([](MotionClip* clip) { clip->root_pos[15].x() += 1.0; });
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(verdict.reason.rfind("body_speed: ", 0), 0u) << verdict.reason;
  EXPECT_NE(verdict.reason.find("between frames 1"), std::string::npos) << verdict.reason;
  EXPECT_NE(verdict.reason.find(" 15"), std::string::npos) << verdict.reason;

  const std::vector<float> low(30, 0.2f), high(30, 0.8f), bad = {0.9f, 1.5f}, none;
  verdict = CheckPlausibility(spec, walk, ShippedClipOptions(), &low);
  EXPECT_FALSE(verdict.accepted);
  EXPECT_EQ(verdict.reason.rfind("discriminator: ", 0), 0u) << verdict.reason;
  EXPECT_NE(verdict.reason.find("sample"), std::string::npos) << verdict.reason;
  EXPECT_TRUE(CheckPlausibility(spec, walk, ShippedClipOptions(), &high).accepted);
  EXPECT_FALSE(CheckPlausibility(spec, walk, ShippedClipOptions(), &bad).accepted);
  EXPECT_FALSE(CheckPlausibility(spec, walk, ShippedClipOptions(), &none).accepted);

  // The defaults are strict about limits: the shipped walk itself is out of range today.
  verdict = CheckPlausibility(spec, walk, PlausibilityOptions());
  if (!verdict.accepted) EXPECT_EQ(verdict.reason.rfind("joint_limit: ", 0), 0u) << verdict.reason;
}

// Variants are judged against their parent: defects they inherit pass, defects they add do not.
TEST(PlausibilityFilterTest, VariantsAreJudgedAgainstTheirParent) {
  const HumanoidSpec& spec = DefaultSpec();
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  // The retargeted walk is out of PHC's knee ranges by a few degrees: strict absolute checks fail it...
  ASSERT_FALSE(CheckPlausibility(spec, walk, PlausibilityOptions()).accepted);
  // ...but an unchanged copy adds nothing, and neither does an arm variant.
  EXPECT_TRUE(CheckVariantPlausibility(spec, walk, walk, PlausibilityOptions()).accepted);
  VariantOptions options;
  options.part = 4;  // R_Arm
  options.count = 2;
  for (const MotionVariant& variant : Generate(walk, options)) {
    const PlausibilityVerdict verdict = CheckVariantPlausibility(spec, variant.clip, walk, PlausibilityOptions());
    EXPECT_TRUE(verdict.accepted) << variant.clip.name << ": " << verdict.reason;
  }
  // A knee bent far past what the parent does, a sunk root, or a teleport are refused.
  auto verdict_after = [&](const std::function<void(MotionClip*)>& plant) {
    MotionClip clip = walk;
    plant(&clip);
    EXPECT_TRUE(ComputeClipKinematics(spec, &clip).ok());
    return CheckVariantPlausibility(spec, clip, walk, PlausibilityOptions());
  };
  const int knee = spec.BodyIndex("L_Knee");
  PlausibilityVerdict verdict = verdict_after([&](MotionClip* clip) {
    for (int f = 0; f < clip->num_frames; ++f) clip->local(f, knee) = HingeRotation(0.0, 1.2, 0.0);
  });
  EXPECT_EQ(verdict.reason.rfind("joint_limit: L_Knee_", 0), 0u) << verdict.reason;
  verdict = verdict_after([](MotionClip* clip) {
    for (Vec3& p : clip->root_pos) p.z() -= 0.2;
  });
  EXPECT_EQ(verdict.reason.rfind("penetration: ", 0), 0u) << verdict.reason;
  verdict = verdict_after([](MotionClip* clip) { clip->root_pos[15].x() += 1.0; });
  EXPECT_EQ(verdict.reason.rfind("body_speed: ", 0), 0u) << verdict.reason;
}

TEST(MotionVariantsTest, BadOptionsAreErrorsNamingTheField) {
  const MotionClip& walk = ShippedClip("deepmimic_walk");
  auto error = [&](const MotionClip& parent, const VariantOptions& options) -> std::string {
    auto variants = GenerateVariants(DefaultSpec(), FivePartLayout(), parent, options);
    if (variants.ok()) return "ok";
    EXPECT_EQ(variants.status().code(), absl::StatusCode::kInvalidArgument);
    return std::string(variants.status().message());
  };
  auto with = [](auto set) {
    VariantOptions options;
    set(options);
    return options;
  };
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.count = 0; })).find("count"), std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.count = 65; })).find("count"), std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.part = 5; })).find("part"), std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.part = -2; })).find("part"), std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.rotation_amplitude = -0.1; })).find("rotation_amplitude"),
            std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.rotation_amplitude = 1.6; })).find("rotation_amplitude"),
            std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.rotation_amplitude = std::nan(""); }))
                .find("rotation_amplitude"),
            std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.time_warp_amplitude = -0.01; })).find("time_warp_amplitude"),
            std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.time_warp_amplitude = 0.95; })).find("time_warp_amplitude"),
            std::string::npos);
  EXPECT_NE(error(walk, with([](VariantOptions& o) { o.knots = 1; })).find("knots"), std::string::npos);

  MotionClip bare = walk;
  bare.body_pos.clear();
  EXPECT_NE(error(bare, VariantOptions()).find("kinematics"), std::string::npos);
  MotionClip one_frame = walk;
  one_frame.num_frames = 1;
  one_frame.root_pos.resize(1);
  one_frame.local_rot.resize(walk.num_bodies);
  EXPECT_NE(error(one_frame, VariantOptions()).find("num_frames"), std::string::npos);
  // The limits themselves are fine.
  EXPECT_EQ(error(walk, with([](VariantOptions& o) {
              o.count = 64;
              o.part = 4;
              o.rotation_amplitude = 1.5;
              o.knots = 64;
            })),
            "ok");
}

}  // namespace
}  // namespace modskill
