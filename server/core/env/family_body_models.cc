#include "server/core/env/family_body_models.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "common/policy/family_parameters.h"

namespace modskill {
namespace {

int Quantize(double scale) { return static_cast<int>(std::lround(scale / kBodyScaleResolution)); }

}  // namespace

BodyScaling FamilyBodyScaling(const HumanoidSpec& spec, double leg_scale, double arm_scale) {
  BodyScaling scaling;
  for (const BodySpec& body : spec.bodies()) {
    const double scale = FamilyLimbScale(body.name, leg_scale, arm_scale);
    if (scale == 1.0) continue;
    scaling.length_by_body[body.name] = scale;
    scaling.radius_by_body[body.name] = scale;
  }
  return scaling;
}

absl::Status ScaleClip(const MotionClip& clip, const HumanoidSpec& scaled, double leg_scale, MotionClip* out) {
  out->name = clip.name;
  out->fps = clip.fps;
  out->num_frames = clip.num_frames;
  out->num_bodies = clip.num_bodies;
  out->local_rot = clip.local_rot;
  out->root_pos.resize(clip.root_pos.size());
  const Vec3 start = clip.root_pos.empty() ? Vec3::Zero() : clip.root_pos[0];
  for (size_t f = 0; f < clip.root_pos.size(); ++f) out->root_pos[f] = start + leg_scale * (clip.root_pos[f] - start);
  if (absl::Status status = ComputeClipKinematics(scaled, out); !status.ok()) return status;
  return PlaceOnGround(scaled, out);
}

absl::StatusOr<std::shared_ptr<const HumanoidModel>> FamilyBodyModels::Get(double leg_scale, double arm_scale) {
  const std::pair<int, int> key{Quantize(leg_scale), Quantize(arm_scale)};
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = cache_.find(key); it != cache_.end()) return it->second;
  auto spec = base_->spec().Scaled(FamilyBodyScaling(base_->spec(), key.first * kBodyScaleResolution,
                                                     key.second * kBodyScaleResolution));
  if (!spec.ok()) return spec.status();
  auto model = HumanoidModel::Create(*spec, base_->options());
  if (!model.ok()) return model.status();
  // An env copies these numbers into its own model (mj_copyModel), which needs the same layout.
  const mjModel* m = (*model)->model();
  const mjModel* b = base_->model();
  if (m->nbuffer != b->nbuffer || m->nbody != b->nbody || m->ngeom != b->ngeom || m->nu != b->nu) {
    return absl::InternalError(absl::StrCat("family body scale ", leg_scale, "/", arm_scale,
                                            ": the scaled model's layout differs from the session's"));
  }
  cache_[key] = *model;
  order_.push_back(key);
  if (order_.size() > kMaxCachedBodyModels) {
    cache_.erase(order_.front());
    order_.pop_front();
  }
  return *model;
}

}  // namespace modskill
