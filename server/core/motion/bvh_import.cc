// CMU BVH (31-joint cgspeed skeleton, y-up, ZYX Euler degrees) retargeted onto the humanoid.
#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "server/core/motion/bvh_parser.h"
#include "server/core/motion/motion_import.h"
#include "server/core/motion/retarget.h"

namespace modskill {
namespace {

// Feet take the shin's rest correction (their nearest mapped ancestor's) instead of matching the
// foot bone, whose slope differs between the skeletons. Mean stance pitch (stance_feet.h) of
// cmu_01_01 / 02_01 / 131_01 this way: +1.3 / +4.2 / -3.7 deg; keeping CMU's own foot
// orientation (the pelvis's correction only): -4.7 / -2.2 / -5.5 deg.
RetargetMap CmuRetargetMap() {
  using K = BodyMapping::Kind;
  RetargetMap map;
  map.bodies = {
      {"Pelvis", K::kMapped, "Hips", "", ""},
      {"L_Hip", K::kMapped, "LeftUpLeg", "LeftLeg", "L_Knee"},
      {"L_Knee", K::kMapped, "LeftLeg", "LeftFoot", "L_Ankle"},
      {"L_Ankle", K::kMapped, "LeftFoot", "", ""},
      {"L_Toe", K::kMapped, "LeftToeBase", "", ""},
      {"R_Hip", K::kMapped, "RightUpLeg", "RightLeg", "R_Knee"},
      {"R_Knee", K::kMapped, "RightLeg", "RightFoot", "R_Ankle"},
      {"R_Ankle", K::kMapped, "RightFoot", "", ""},
      {"R_Toe", K::kMapped, "RightToeBase", "", ""},
      {"Torso", K::kMapped, "LowerBack", "Spine", "Spine"},
      {"Spine", K::kMapped, "Spine", "Spine1", "Chest"},
      {"Chest", K::kMapped, "Spine1", "Neck", "Neck"},
      {"Neck", K::kMapped, "Neck1", "Head", "Head"},
      {"Head", K::kMapped, "Head", "", ""},
      {"L_Thorax", K::kMapped, "LeftShoulder", "LeftArm", "L_Shoulder"},
      {"L_Shoulder", K::kMapped, "LeftArm", "LeftForeArm", "L_Elbow"},
      {"L_Elbow", K::kMapped, "LeftForeArm", "LeftHand", "L_Wrist"},
      {"L_Wrist", K::kMapped, "LeftHand", "LeftFingerBase", "L_Hand"},
      {"L_Hand", K::kMapped, "LeftFingerBase", "", ""},
      {"R_Thorax", K::kMapped, "RightShoulder", "RightArm", "R_Shoulder"},
      {"R_Shoulder", K::kMapped, "RightArm", "RightForeArm", "R_Elbow"},
      {"R_Elbow", K::kMapped, "RightForeArm", "RightHand", "R_Wrist"},
      {"R_Wrist", K::kMapped, "RightHand", "RightFingerBase", "R_Hand"},
      {"R_Hand", K::kMapped, "RightFingerBase", "", ""},
  };
  map.left_hip = "LeftUpLeg";
  map.left_knee = "LeftLeg";
  map.left_ankle = "LeftFoot";
  map.right_hip = "RightUpLeg";
  return map;
}

// The cgspeed "3dsMax-friendly" release names the same 31 joints differently.
std::string CmuJointAlias(const std::string& name) {
  static const std::pair<const char*, const char*> kAliases[] = {
      {"LeftUpLeg", "LeftHip"},        {"LeftLeg", "LeftKnee"},         {"LeftFoot", "LeftAnkle"},
      {"LeftToeBase", "LeftToe"},      {"RightUpLeg", "RightHip"},      {"RightLeg", "RightKnee"},
      {"RightFoot", "RightAnkle"},     {"RightToeBase", "RightToe"},    {"LowerBack", "lowerback"},
      {"Spine", "Chest"},              {"Spine1", "Chest2"},            {"Neck", "lowerneck"},
      {"Neck1", "Neck"},               {"LeftShoulder", "LeftCollar"},  {"LeftArm", "LeftShoulder"},
      {"LeftForeArm", "LeftElbow"},    {"LeftHand", "LeftWrist"},       {"LeftFingerBase", "lhand"},
      {"RightShoulder", "RightCollar"}, {"RightArm", "RightShoulder"},  {"RightForeArm", "RightElbow"},
      {"RightHand", "RightWrist"},     {"RightFingerBase", "rhand"},
  };
  for (const auto& [motionbuilder, max] : kAliases) {
    if (name == motionbuilder) return max;
  }
  return name;
}

// Renames every source joint of `map` to the 3dsMax-friendly names.
RetargetMap WithMaxNames(RetargetMap map) {
  for (BodyMapping& body : map.bodies) {
    body.source = CmuJointAlias(body.source);
    if (!body.source_direction.empty()) body.source_direction = CmuJointAlias(body.source_direction);
  }
  for (std::string* joint : {&map.left_hip, &map.left_knee, &map.left_ankle, &map.right_hip}) *joint = CmuJointAlias(*joint);
  return map;
}

// Mean rotation angle (rad) between the local joint rotations of frames a and b.
double MeanJointTurn(const BvhClip& bvh, int a, int b) {
  double total = 0;
  for (int j = 0; j < bvh.num_joints(); ++j) total += bvh.LocalRotation(a, j).angularDistance(bvh.LocalRotation(b, j));
  return total / bvh.num_joints();
}

}  // namespace

int LeadingCalibrationFrames(const BvhClip& bvh) {
  // CMU's first frame is the actor's calibration pose (most joint angles zero), then the take
  // starts: a jump of ~10 degrees per joint between frames 0 and 1 against a fraction of a degree
  // between the frames after. Left in, every episode and evaluation that starts at frame 0
  // starts from a pose the take never passes through.
  constexpr double kMinJump = 5.0 * M_PI / 180, kJumpOverMotion = 10;
  int dropped = 0;
  while (dropped < 3 && bvh.num_frames - dropped >= 4) {
    const double jump = MeanJointTurn(bvh, dropped, dropped + 1);
    const double motion = MeanJointTurn(bvh, dropped + 1, dropped + 2);
    if (!(jump > kMinJump && jump > kJumpOverMotion * motion)) break;
    ++dropped;
  }
  return dropped;
}

absl::StatusOr<MotionClip> ImportCmuBvh(const std::string& path, const HumanoidSpec& spec,
                                        const ResourceLimits& limits) {
  auto bvh = ReadBvhFile(path);
  if (!bvh.ok()) return bvh.status();
  if (!(bvh->frame_time > 0)) return absl::InvalidArgumentError(absl::StrCat(path, ": Frame Time must be > 0"));
  if (auto status = ValidateClipTiming(1.0 / bvh->frame_time, bvh->num_frames,
                                       absl::StrCat(path, ": Frame Time ", bvh->frame_time), limits);
      !status.ok()) {
    return status;
  }
  if (const int calibration = LeadingCalibrationFrames(*bvh); calibration > 0) {
    bvh->num_frames -= calibration;
    bvh->root_translation.erase(bvh->root_translation.begin(), bvh->root_translation.begin() + calibration);
    bvh->local_rotation.erase(bvh->local_rotation.begin(),
                              bvh->local_rotation.begin() + static_cast<size_t>(calibration) * bvh->num_joints());
  }
  RetargetSource source;
  source.what = path;
  source.num_frames = bvh->num_frames;
  source.fps = 1.0 / bvh->frame_time;
  for (const BvhJoint& joint : bvh->joints) {
    source.joint_names.push_back(joint.name);
    source.parents.push_back(joint.parent);
    source.rest_offsets.push_back(joint.offset);
  }
  source.local_rot = bvh->local_rotation;
  source.root_pos = bvh->root_translation;
  source.to_world = YupToZupMatrix();
  const bool max_names = bvh->JointIndex("LeftUpLeg") < 0 && bvh->JointIndex("LeftHip") >= 0;
  return RetargetToHumanoid(source, max_names ? WithMaxNames(CmuRetargetMap()) : CmuRetargetMap(), spec);
}

}  // namespace modskill
