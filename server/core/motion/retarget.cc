#include "server/core/motion/retarget.h"

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace modskill {
namespace {

int IndexOf(const std::vector<std::string>& names, const std::string& name) {
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

// Rest poses in the simulation frame.
std::vector<Vec3> SourceRestPositions(const RetargetSource& source) {
  const int joints = static_cast<int>(source.joint_names.size());
  std::vector<Vec3> source_rest(joints, Vec3::Zero());
  for (int j = 1; j < joints; ++j) {
    source_rest[j] = source_rest[source.parents[j]] + source.to_world * source.rest_offsets[j];
  }
  return source_rest;
}

absl::StatusOr<int> SourceIndex(const RetargetSource& source, const std::string& name, const std::string& role) {
  const int index = IndexOf(source.joint_names, name);
  if (index < 0) return absl::InvalidArgumentError(absl::StrCat(source.what, ": unknown joint name '", name, "' (", role, ")"));
  return index;
}

// The source skeleton and its frames agree in size, with at least 2 frames.
absl::Status CheckSource(const RetargetSource& source) {
  const int joints = static_cast<int>(source.joint_names.size());
  if (joints == 0 || source.parents.size() != static_cast<size_t>(joints) ||
      source.rest_offsets.size() != static_cast<size_t>(joints)) {
    return absl::InvalidArgumentError(absl::StrCat(source.what, ": inconsistent source skeleton"));
  }
  if (source.num_frames < 2 || source.local_rot.size() != static_cast<size_t>(source.num_frames) * joints ||
      source.root_pos.size() != static_cast<size_t>(source.num_frames)) {
    return absl::InvalidArgumentError(absl::StrCat(source.what, ": need at least 2 frames of consistent size"));
  }
  return absl::OkStatus();
}

// How the source is fitted to the humanoid at rest: the length scale (target leg / source leg)
// and the rotation that turns the source's rest facing into the simulation's.
struct RestFit {
  double scale = 1;
  Quat root_alignment;
};

absl::StatusOr<RestFit> FitRest(const RetargetSource& source, const RetargetMap& map, const HumanoidSpec& spec,
                                const std::vector<Vec3>& source_rest, const std::vector<Vec3>& target_rest) {
  auto l_hip = SourceIndex(source, map.left_hip, "left_hip");
  auto l_knee = SourceIndex(source, map.left_knee, "left_knee");
  auto l_ankle = SourceIndex(source, map.left_ankle, "left_ankle");
  auto r_hip = SourceIndex(source, map.right_hip, "right_hip");
  for (const auto* s : {&l_hip, &l_knee, &l_ankle, &r_hip}) {
    if (!s->ok()) return s->status();
  }
  const double source_leg = (source_rest[*l_knee] - source_rest[*l_hip]).norm() +
                            (source_rest[*l_ankle] - source_rest[*l_knee]).norm();
  const int t_hip = spec.BodyIndex("L_Hip"), t_knee = spec.BodyIndex("L_Knee"), t_ankle = spec.BodyIndex("L_Ankle");
  if (t_hip < 0 || t_knee < 0 || t_ankle < 0) return absl::InvalidArgumentError("skeleton lacks L_Hip/L_Knee/L_Ankle");
  const double target_leg = (target_rest[t_knee] - target_rest[t_hip]).norm() +
                            (target_rest[t_ankle] - target_rest[t_knee]).norm();
  if (!(source_leg > 1e-9)) return absl::InvalidArgumentError(absl::StrCat(source.what, ": degenerate leg at rest"));
  RestFit fit;
  fit.scale = target_leg / source_leg;

  // The source's rest facing: left is from the right hip to the left hip; forward = left x up.
  Vec3 left = source_rest[*l_hip] - source_rest[*r_hip];
  left.z() = 0;
  if (left.norm() < 1e-9) return absl::InvalidArgumentError(absl::StrCat(source.what, ": hips coincide at rest"));
  left.normalize();
  const Vec3 up = Vec3::UnitZ();
  const Vec3 forward = left.cross(up);
  Mat3 facing;
  facing.col(0) = forward;
  facing.col(1) = left;
  facing.col(2) = up;
  fit.root_alignment = Quat(facing);
  return fit;
}

// Per target body: kind, source joint, and the rest-pose correction B (G_target = G_source * B).
struct BodyPlan {
  std::vector<BodyMapping::Kind> kind;
  std::vector<int> source_of;
  std::vector<Quat> correction;
};

absl::StatusOr<BodyPlan> PlanBodies(const RetargetSource& source, const RetargetMap& map, const HumanoidSpec& spec,
                                    const std::vector<Vec3>& source_rest, const std::vector<Vec3>& target_rest,
                                    const Quat& root_alignment) {
  const int bodies = spec.num_bodies();
  BodyPlan plan;
  plan.kind.assign(bodies, BodyMapping::Kind::kFollowParent);
  plan.source_of.assign(bodies, -1);
  plan.correction.assign(bodies, root_alignment);
  std::vector<bool> has_direction(bodies, false);
  for (const BodyMapping& m : map.bodies) {
    const int t = spec.BodyIndex(m.target);
    if (t < 0) return absl::InvalidArgumentError(absl::StrCat("retarget map: unknown target body '", m.target, "'"));
    plan.kind[t] = m.kind;
    if (m.kind != BodyMapping::Kind::kMapped) continue;
    auto s = SourceIndex(source, m.source, m.target);
    if (!s.ok()) return s.status();
    plan.source_of[t] = *s;
    if (!m.source_direction.empty()) {
      auto sd = SourceIndex(source, m.source_direction, m.target + " direction");
      if (!sd.ok()) return sd.status();
      const int td = spec.BodyIndex(m.target_direction);
      if (td < 0) return absl::InvalidArgumentError(absl::StrCat("retarget map: unknown body '", m.target_direction, "'"));
      const Vec3 d_target = root_alignment * (target_rest[td] - target_rest[t]);
      const Vec3 d_source = source_rest[*sd] - source_rest[*s];
      if (d_target.norm() > 1e-9 && d_source.norm() > 1e-9) {
        plan.correction[t] = RotationBetween(d_target, d_source) * root_alignment;
        has_direction[t] = true;
      }
    }
  }
  if (plan.kind[0] != BodyMapping::Kind::kMapped) return absl::InvalidArgumentError("retarget map: the root must be mapped");
  // Leaves without a direction of their own inherit the correction of their nearest mapped ancestor.
  for (int t = 1; t < bodies; ++t) {
    if (plan.kind[t] == BodyMapping::Kind::kMapped && !has_direction[t]) {
      for (int a = spec.body(t).parent; a >= 0; a = spec.body(a).parent) {
        if (plan.kind[a] == BodyMapping::Kind::kMapped) {
          plan.correction[t] = plan.correction[a];
          break;
        }
      }
    }
  }
  return plan;
}

// Spread chains: a -> u1 -> ... -> uk -> m share the rotation from a to m evenly.
void SpreadChains(const HumanoidSpec& spec, const std::vector<BodyMapping::Kind>& kind,
                  std::vector<Quat>& target_global) {
  const int bodies = spec.num_bodies();
  for (int t = 1; t < bodies; ++t) {
    if (kind[t] != BodyMapping::Kind::kSpread) continue;
    int ancestor = spec.body(t).parent, position = 1;
    while (kind[ancestor] == BodyMapping::Kind::kSpread) {
      ancestor = spec.body(ancestor).parent;
      ++position;
    }
    int descendant = t, chain = 1;
    for (bool found = true; found && kind[descendant] != BodyMapping::Kind::kMapped;) {
      found = false;
      for (int c = descendant + 1; c < bodies; ++c) {
        if (spec.body(c).parent == descendant &&
            (kind[c] == BodyMapping::Kind::kSpread || kind[c] == BodyMapping::Kind::kMapped)) {
          if (kind[c] == BodyMapping::Kind::kSpread) ++chain;
          descendant = c;
          found = true;
          break;
        }
      }
    }
    if (kind[descendant] != BodyMapping::Kind::kMapped) continue;  // nothing to share: follow parent
    const int total_links = position + chain - 1 + 1;  // spread bodies + the mapped one
    const Quat relative = target_global[ancestor].conjugate() * target_global[descendant];
    target_global[t] = target_global[ancestor] * Quat::Identity().slerp(static_cast<double>(position) / total_links, relative);
  }
}

// One frame: the source's global rotations, mapped onto the target bodies, written as local rotations.
void RetargetFrame(const RetargetSource& source, const HumanoidSpec& spec, const BodyPlan& plan, double scale,
                   int f, std::vector<Quat>& source_global, std::vector<Quat>& target_global, MotionClip& clip) {
  const int joints = static_cast<int>(source.joint_names.size());
  const int bodies = spec.num_bodies();
  const Mat3& w = source.to_world;
  const Quat w_quat(w);
  for (int j = 0; j < joints; ++j) {
    const Quat& local = source.local_rot[f * joints + j];
    source_global[j] = j == 0 ? local : source_global[source.parents[j]] * local;
  }
  for (int t = 0; t < bodies; ++t) {
    if (plan.kind[t] == BodyMapping::Kind::kMapped) {
      // Express the source rotation in the simulation frame: W * G * W^T.
      target_global[t] =
          (w_quat * source_global[plan.source_of[t]] * w_quat.conjugate() * plan.correction[t]).normalized();
    } else {
      target_global[t] = target_global[spec.body(t).parent];
    }
  }
  SpreadChains(spec, plan.kind, target_global);
  for (int t = 0; t < bodies; ++t) {
    clip.local(f, t) = t == 0 ? target_global[0]
                              : (target_global[spec.body(t).parent].conjugate() * target_global[t]).normalized();
  }
  clip.root_pos[f] = scale * (w * source.root_pos[f]);
}

}  // namespace

Mat3 YupToZupMatrix() {
  Mat3 w;
  w << 0, 0, 1,  //
      1, 0, 0,   //
      0, 1, 0;
  return w;
}

absl::StatusOr<MotionClip> RetargetToHumanoid(const RetargetSource& source, const RetargetMap& map,
                                              const HumanoidSpec& spec) {
  if (absl::Status status = CheckSource(source); !status.ok()) return status;
  const std::vector<Vec3> source_rest = SourceRestPositions(source);
  const std::vector<Vec3> target_rest = spec.RestPositions();
  auto fit = FitRest(source, map, spec, source_rest, target_rest);
  if (!fit.ok()) return fit.status();
  auto plan = PlanBodies(source, map, spec, source_rest, target_rest, fit->root_alignment);
  if (!plan.ok()) return plan.status();

  const int bodies = spec.num_bodies();
  MotionClip clip;
  clip.num_frames = source.num_frames;
  clip.num_bodies = bodies;
  clip.fps = source.fps;
  clip.root_pos.resize(source.num_frames);
  clip.local_rot.resize(static_cast<size_t>(source.num_frames) * bodies);
  std::vector<Quat> source_global(source.joint_names.size()), target_global(bodies);
  for (int f = 0; f < source.num_frames; ++f) {
    RetargetFrame(source, spec, *plan, fit->scale, f, source_global, target_global, clip);
  }
  return clip;
}

}  // namespace modskill
