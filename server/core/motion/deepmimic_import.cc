// DeepMimic humanoid3d clips (JSON frames of 44 numbers, y-up, facing +x) retargeted onto the
// humanoid. Frame layout and the character's joint offsets: data/motions/source/deepmimic.
#include <cmath>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "server/core/motion/motion_import.h"
#include "server/core/motion/retarget.h"

namespace modskill {
namespace {

// The humanoid3d character (data/motions/source/deepmimic/humanoid3d.txt): joint, parent, offset.
struct DeepMimicJoint {
  const char* name;
  int parent;
  double x, y, z;
};
constexpr DeepMimicJoint kJoints[] = {
    {"root", -1, 0, 0, 0},
    {"chest", 0, 0, 0.236151, 0},
    {"neck", 1, 0, 0.223894, 0},
    {"right_hip", 0, 0, 0, 0.084887},
    {"right_knee", 3, 0, -0.421546, 0},
    {"right_ankle", 4, 0, -0.40987, 0},
    {"right_shoulder", 1, -0.02405, 0.2435, 0.18311},
    {"right_elbow", 6, 0, -0.274788, 0},
    {"right_wrist", 7, 0, -0.258947, 0},
    {"left_hip", 0, 0, 0, -0.084887},
    {"left_knee", 9, 0, -0.421546, 0},
    {"left_ankle", 10, 0, -0.40987, 0},
    {"left_shoulder", 1, -0.02405, 0.2435, -0.18311},
    {"left_elbow", 12, 0, -0.274788, 0},
    {"left_wrist", 13, 0, -0.258947, 0},
    {"head_top", 2, 0, 0.25, 0},  // not in the file: a direction for the neck bone
};
constexpr int kNumJoints = sizeof(kJoints) / sizeof(kJoints[0]);

// Where each joint's rotation sits in a frame: offset of a quaternion (w, x, y, z) or, for
// revolute knees and elbows, of one angle about z. -1: no rotation in the file.
struct FrameSlot {
  int offset;
  bool revolute;
};
constexpr FrameSlot kSlots[kNumJoints] = {
    {4, false},  {8, false},  {12, false}, {16, false}, {20, true},  {21, false}, {25, false}, {29, true},
    {-1, false}, {30, false}, {34, true},  {35, false}, {39, false}, {43, true},  {-1, false}, {-1, false}};
constexpr int kFrameWidth = 44;

RetargetMap DeepMimicRetargetMap() {
  using K = BodyMapping::Kind;
  RetargetMap map;
  map.bodies = {
      {"Pelvis", K::kMapped, "root", "", ""},
      {"L_Hip", K::kMapped, "left_hip", "left_knee", "L_Knee"},
      {"L_Knee", K::kMapped, "left_knee", "left_ankle", "L_Ankle"},
      {"L_Ankle", K::kMapped, "left_ankle", "", ""},
      {"R_Hip", K::kMapped, "right_hip", "right_knee", "R_Knee"},
      {"R_Knee", K::kMapped, "right_knee", "right_ankle", "R_Ankle"},
      {"R_Ankle", K::kMapped, "right_ankle", "", ""},
      {"Torso", K::kSpread, "", "", ""},
      {"Spine", K::kSpread, "", "", ""},
      {"Chest", K::kMapped, "chest", "neck", "Neck"},
      {"Neck", K::kMapped, "neck", "head_top", "Head"},
      {"L_Shoulder", K::kMapped, "left_shoulder", "left_elbow", "L_Elbow"},
      {"L_Elbow", K::kMapped, "left_elbow", "left_wrist", "L_Wrist"},
      {"R_Shoulder", K::kMapped, "right_shoulder", "right_elbow", "R_Elbow"},
      {"R_Elbow", K::kMapped, "right_elbow", "right_wrist", "R_Wrist"},
  };
  map.left_hip = "left_hip";
  map.left_knee = "left_knee";
  map.left_ankle = "left_ankle";
  map.right_hip = "right_hip";
  return map;
}

}  // namespace

absl::StatusOr<MotionClip> ImportDeepMimicText(absl::string_view text, absl::string_view what,
                                               const HumanoidSpec& spec, const ResourceLimits& limits) {
  nlohmann::json root = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) return absl::InvalidArgumentError(absl::StrCat(what, ": not valid JSON"));
  if (!root.is_object() || !root.contains("Frames") || !root["Frames"].is_array()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": missing array 'Frames'"));
  }
  const auto& frames = root["Frames"];
  if (frames.size() < 2) return absl::InvalidArgumentError(absl::StrCat(what, ": field 'Frames' needs at least 2 frames"));
  if (frames.size() > static_cast<size_t>(limits.max_clip_frames)) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": field 'Frames' has ", frames.size(),
                                                   " frames, more than the limit of ", limits.max_clip_frames,
                                                   " (max_clip_frames)"));
  }
  RetargetSource source;
  source.what = std::string(what);
  source.num_frames = static_cast<int>(frames.size());
  for (const auto& joint : kJoints) {
    source.joint_names.push_back(joint.name);
    source.parents.push_back(joint.parent);
    source.rest_offsets.emplace_back(joint.x, joint.y, joint.z);
  }
  source.local_rot.assign(static_cast<size_t>(source.num_frames) * kNumJoints, Quat::Identity());
  source.root_pos.resize(source.num_frames);
  for (int f = 0; f < source.num_frames; ++f) {
    const auto& row = frames[f];
    if (!row.is_array() || row.size() != kFrameWidth) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": Frames[", f, "] must hold ", kFrameWidth, " numbers"));
    }
    double v[kFrameWidth];
    for (int k = 0; k < kFrameWidth; ++k) {
      if (!row[k].is_number() || !std::isfinite(row[k].get<double>())) {
        return absl::InvalidArgumentError(absl::StrCat(what, ": Frames[", f, "][", k, "] is not a finite number"));
      }
      v[k] = row[k].get<double>();
    }
    if (f == 0) {
      if (!(v[0] > 0)) return absl::InvalidArgumentError(absl::StrCat(what, ": Frames[0][0] (dt) must be > 0"));
      source.fps = 1.0 / v[0];
      if (auto status = ValidateClipTiming(source.fps, source.num_frames,
                                           absl::StrCat(what, ": Frames[0][0] (dt) ", v[0]), limits);
          !status.ok()) {
        return status;
      }
    }
    source.root_pos[f] = Vec3(v[1], v[2], v[3]);
    for (int j = 0; j < kNumJoints; ++j) {
      const FrameSlot slot = kSlots[j];
      if (slot.offset < 0) continue;
      Quat q = slot.revolute ? Quat(Eigen::AngleAxisd(v[slot.offset], Vec3::UnitZ()))
                             : Quat(v[slot.offset], v[slot.offset + 1], v[slot.offset + 2], v[slot.offset + 3]);
      if (q.norm() < 1e-6) {
        return absl::InvalidArgumentError(absl::StrCat(what, ": Frames[", f, "] joint '", kJoints[j].name,
                                                       "' has a zero quaternion"));
      }
      source.local_rot[f * kNumJoints + j] = q.normalized();
    }
  }
  source.to_world = YupToZupMatrix();
  return RetargetToHumanoid(source, DeepMimicRetargetMap(), spec);
}

absl::StatusOr<MotionClip> ImportDeepMimic(const std::string& path, const HumanoidSpec& spec,
                                           const ResourceLimits& limits) {
  auto text = ReadFileToString(path, size_t{256} << 20);
  if (!text.ok()) return text.status();
  return ImportDeepMimicText(*text, path, spec, limits);
}

}  // namespace modskill
