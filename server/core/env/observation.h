// Tracking and AMP observations (docs/DESIGN.md sections 2 and 3), written straight into a row of
// the batch buffer. Everything is expressed in the agent's heading frame.
#ifndef MODSKILL_SERVER_CORE_ENV_OBSERVATION_H_
#define MODSKILL_SERVER_CORE_ENV_OBSERVATION_H_

#include "server/core/env/env_spec.h"
#include "server/core/env/humanoid_state.h"

namespace modskill {

// Writes spec.obs_size floats: per body in part order, [self | task] where task compares
// `sim` with `target` (the reference at the next control step).
void WriteTrackingObservation(const EnvSpec& spec, const HumanoidState& sim, const HumanoidState& target, float* out);

// A tracker observing several reference frames: writes every body's task block `k` (1 for the
// frame after the next, ...; block 0 is WriteTrackingObservation's) comparing `sim` with
// `upcoming`, the reference k control steps after the next one.
void WriteUpcomingReferenceObservation(const EnvSpec& spec, const HumanoidState& sim, const HumanoidState& upcoming,
                                       int k, float* out);

// Task envs: writes every body's self features at its place in obs (spec.body_obs_start), the
// same values WriteTrackingObservation writes there; the goal is the task's to write.
void WriteSelfObservation(const EnvSpec& spec, const HumanoidState& sim, float* out);

// The kTaskFeaturesPerBody reference features of one body, as tracking observes them (the VR
// task's goal holds those of the head and the hands).
void WriteBodyTaskFeatures(const HumanoidState& sim, const HumanoidState& target, int body, float* out);

// Writes spec.amp_obs_per_frame floats describing one frame of `state`.
void WriteAmpFrame(const EnvSpec& spec, const HumanoidState& state, float* out);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_OBSERVATION_H_
