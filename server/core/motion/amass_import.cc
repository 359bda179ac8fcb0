// AMASS / SMPL(-H) .npz: axis-angle poses in SMPL joint order, y-up body template, z-up world.
#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "server/core/motion/motion_import.h"
#include "server/core/motion/npz_reader.h"
#include "server/core/motion/retarget.h"

namespace modskill {
namespace {

// SMPL joint order (the layout of `poses`) for each of our bodies, by name.
constexpr const char* kSmplJointOrder[24] = {
    "Pelvis",   "L_Hip",    "R_Hip",      "Torso",      "L_Knee",  "R_Knee",  "Spine",   "L_Ankle",
    "R_Ankle",  "Chest",    "L_Toe",      "R_Toe",      "Neck",    "L_Thorax", "R_Thorax", "Head",
    "L_Shoulder", "R_Shoulder", "L_Elbow", "R_Elbow",  "L_Wrist", "R_Wrist", "L_Hand",  "R_Hand"};

// Pelvis joint of the SMPL neutral template (y-up). SMPL rotates the body about this joint, so
// the world pelvis is J0 + trans whatever the root rotation.
const Vec3 kTemplatePelvisYup(-0.0018, -0.2233, 0.0282);

}  // namespace

absl::StatusOr<MotionClip> ImportAmassNpz(const std::string& path, const HumanoidSpec& spec,
                                          const ResourceLimits& limits) {
  auto archive = ReadNpz(path, limits);
  if (!archive.ok()) return archive.status();
  auto member = [&](const char* name) -> const NpyArray* {
    auto it = archive->find(name);
    return it == archive->end() ? nullptr : &it->second;
  };
  const NpyArray* poses = member("poses");
  const NpyArray* trans = member("trans");
  const NpyArray* rate = member("mocap_framerate");
  if (rate == nullptr) rate = member("mocap_frame_rate");
  if (poses == nullptr) return absl::InvalidArgumentError(absl::StrCat(path, ": missing field 'poses'"));
  if (trans == nullptr) return absl::InvalidArgumentError(absl::StrCat(path, ": missing field 'trans'"));
  if (rate == nullptr) return absl::InvalidArgumentError(absl::StrCat(path, ": missing field 'mocap_framerate'"));
  // Text members (dtype <U or |S) carry no numbers.
  for (const auto& [field, array] : {std::pair<const char*, const NpyArray*>{"poses", poses}, {"trans", trans},
                                     {"mocap_framerate", rate}}) {
    if (array->data.size() != static_cast<size_t>(array->size())) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": field '", field, "' must be numeric, got dtype ", array->dtype));
    }
  }
  if (poses->shape.size() != 2 || (poses->shape[1] != 72 && poses->shape[1] != 156 && poses->shape[1] != 165)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": field 'poses' must be N x 72 (SMPL), N x 156 (SMPL-H) or "
                                                   "N x 165 (SMPL-X), got ", poses->shape.size(), "-d shape"));
  }
  const int64_t frames = poses->shape[0];
  const int64_t width = poses->shape[1];
  if (trans->shape.size() != 2 || trans->shape[0] != frames || trans->shape[1] != 3) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": field 'trans' must be ", frames, " x 3"));
  }
  if (frames < 2) return absl::InvalidArgumentError(absl::StrCat(path, ": field 'poses' has ", frames, " frames, need >= 2"));
  if (rate->size() != 1) return absl::InvalidArgumentError(absl::StrCat(path, ": field 'mocap_framerate' must be one number"));
  if (auto status = ValidateClipTiming(rate->data[0], frames, absl::StrCat(path, ": field 'mocap_framerate'"), limits);
      !status.ok()) {
    return status;
  }
  for (int64_t i = 0; i < poses->size(); ++i) {
    if (!std::isfinite(poses->data[i])) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": field 'poses' row ", i / width, " is not finite"));
    }
  }
  for (int64_t i = 0; i < trans->size(); ++i) {
    if (!std::isfinite(trans->data[i])) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": field 'trans' row ", i / 3, " is not finite"));
    }
  }
  int body_of_smpl_joint[24];
  for (int j = 0; j < 24; ++j) {
    body_of_smpl_joint[j] = spec.BodyIndex(kSmplJointOrder[j]);
    if (body_of_smpl_joint[j] < 0) return absl::InvalidArgumentError(absl::StrCat("skeleton lacks body ", kSmplJointOrder[j]));
  }
  // SMPL-H and SMPL-X put 22 body joints first, then hands (and face): our L_Hand/R_Hand stay at rest.
  const int body_joints = width == 72 ? 24 : 22;

  const Mat3 p = YupToZupMatrix();
  const Quat p_quat(p);
  MotionClip clip;
  clip.num_frames = static_cast<int>(frames);
  clip.num_bodies = spec.num_bodies();
  clip.fps = rate->data[0];
  clip.root_pos.resize(frames);
  clip.local_rot.assign(static_cast<size_t>(frames) * clip.num_bodies, Quat::Identity());
  for (int64_t f = 0; f < frames; ++f) {
    const double* row = poses->data.data() + f * width;
    for (int j = 0; j < body_joints; ++j) {
      const Quat smpl = QuatFromRotationVector(Vec3(row[3 * j], row[3 * j + 1], row[3 * j + 2]));
      // The body frames of our humanoid are SMPL's rotated by P (y-up -> z-up):
      // root: R_root * P^T; joints: P * R * P^T.
      clip.local(f, body_of_smpl_joint[j]) =
          (j == 0 ? smpl * p_quat.conjugate() : p_quat * smpl * p_quat.conjugate()).normalized();
    }
    const Vec3 t(trans->data[3 * f], trans->data[3 * f + 1], trans->data[3 * f + 2]);
    clip.root_pos[f] = kTemplatePelvisYup + t;
  }
  return clip;
}

}  // namespace modskill
