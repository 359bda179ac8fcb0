#include "server/core/env/observation.h"

namespace modskill {
namespace {

inline void Write3(const Vec3& v, float* out) {
  out[0] = static_cast<float>(v.x());
  out[1] = static_cast<float>(v.y());
  out[2] = static_cast<float>(v.z());
}

// Self: where the body is and how it moves, relative to the root and heading. Returns the end.
float* WriteSelfFeatures(const HumanoidState& sim, int body, const Quat& to_heading, float* o) {
  const Vec3 root_pos = sim.body_pos[0];
  if (body == 0) {
    *o++ = static_cast<float>(root_pos.z());
  } else {
    Write3(to_heading * (sim.body_pos[body] - root_pos), o);
    o += 3;
  }
  WriteTanNorm(to_heading * sim.body_rot[body], o);
  o += 6;
  Write3(to_heading * sim.body_vel[body], o);
  o += 3;
  Write3(to_heading * sim.body_ang_vel[body], o);
  return o + 3;
}

// Task: what is left to the reference, and where the reference is.
void WriteTaskFeatures(const HumanoidState& sim, const HumanoidState& target, int body, const Quat& to_heading,
                       float* o) {
  const Vec3 root_pos = sim.body_pos[0];
  Write3(to_heading * (target.body_pos[body] - sim.body_pos[body]), o);
  o += 3;
  const Quat diff = target.body_rot[body] * sim.body_rot[body].conjugate();
  WriteTanNorm(to_heading * diff * to_heading.conjugate(), o);
  o += 6;
  Write3(to_heading * (target.body_vel[body] - sim.body_vel[body]), o);
  o += 3;
  Write3(to_heading * (target.body_ang_vel[body] - sim.body_ang_vel[body]), o);
  o += 3;
  Write3(to_heading * (target.body_pos[body] - root_pos), o);
  o += 3;
  WriteTanNorm(to_heading * target.body_rot[body], o);
}

}  // namespace

void WriteBodyTaskFeatures(const HumanoidState& sim, const HumanoidState& target, int body, float* out) {
  WriteTaskFeatures(sim, target, body, InverseHeadingRotation(sim.body_rot[0]), out);
}

void WriteTrackingObservation(const EnvSpec& spec, const HumanoidState& sim, const HumanoidState& target, float* out) {
  const Quat to_heading = InverseHeadingRotation(sim.body_rot[0]);
  for (int body : spec.body_order) {
    float* task = WriteSelfFeatures(sim, body, to_heading, out + spec.body_obs_start[body]);
    WriteTaskFeatures(sim, target, body, to_heading, task);
  }
}

void WriteUpcomingReferenceObservation(const EnvSpec& spec, const HumanoidState& sim, const HumanoidState& upcoming,
                                       int k, float* out) {
  const Quat to_heading = InverseHeadingRotation(sim.body_rot[0]);
  for (int body : spec.body_order) {
    const int self = body == 0 ? kSelfFeaturesRoot : kSelfFeaturesPerBody;
    WriteTaskFeatures(sim, upcoming, body, to_heading, out + spec.body_obs_start[body] + self + k * kTaskFeaturesPerBody);
  }
}

void WriteSelfObservation(const EnvSpec& spec, const HumanoidState& sim, float* out) {
  const Quat to_heading = InverseHeadingRotation(sim.body_rot[0]);
  for (int body : spec.body_order) WriteSelfFeatures(sim, body, to_heading, out + spec.body_obs_start[body]);
}

void WriteAmpFrame(const EnvSpec& spec, const HumanoidState& state, float* out) {
  const Vec3 root_pos = state.body_pos[0];
  const Quat root_rot = state.body_rot[0];
  const Quat to_heading = InverseHeadingRotation(root_rot);
  *out++ = static_cast<float>(root_pos.z());
  WriteTanNorm(to_heading * root_rot, out);
  out += 6;
  Write3(to_heading * state.body_vel[0], out);
  out += 3;
  Write3(to_heading * state.body_ang_vel[0], out);
  out += 3;
  const int bodies = static_cast<int>(state.body_rot.size());
  for (int b = 1; b < bodies; ++b) {
    const double* angle = &state.dof_pos[3 * (b - 1)];
    WriteTanNorm(HingeRotation(angle[0], angle[1], angle[2]), out);
    out += 6;
  }
  for (double v : state.dof_vel) *out++ = static_cast<float>(v);
  for (int key : spec.amp_key_bodies) {
    Write3(to_heading * (state.body_pos[key] - root_pos), out);
    out += 3;
  }
}

}  // namespace modskill
