// How a clip's feet stand. A simulated foot that carries the body lies flat on a flat floor; a
// retargeted clip can hold it tilted. The DeepMimic shin is vertical in its rest pose and
// SMPL's leans back 6 degrees, and the ankles take the shin's rest correction, so the shipped
// deepmimic_walk stands +7.7 degrees toe-up (-0.4 with DeepMimic's own foot orientation, which
// tracked no better: README, "Where the walk's error is").
#ifndef MODSKILL_SERVER_CORE_MOTION_STANCE_FEET_H_
#define MODSKILL_SERVER_CORE_MOTION_STANCE_FEET_H_

#include <vector>

#include "server/core/motion/motion_clip.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct StanceFeetOptions {
  double contact_height = 0.03;  // a foot's geometry this close to the floor (m), as FootContactRatio
  double max_speed = 0.5;        // and its ankle slower than this (m/s): the foot carries weight
};

struct StanceFeet {
  int stance_samples = 0;        // (frame, ankle) pairs in stance
  double mean_pitch_deg = 0;     // of the ankle's forward (+x at rest) axis, toe up > 0
  double mean_clearance = 0;     // lowest point of the foot's geometry above the floor (m)
};

// Over every frame where an ankle (with its toe) is in stance. Needs the clip's kinematics.
StanceFeet MeasureStanceFeet(const HumanoidSpec& spec, const MotionClip& clip, const StanceFeetOptions& options = {});

// Per frame: whether a foot carries the body, judged against `floor` (the floor's height under
// each frame): the foot within contact_height of it, its ankle slower than max_speed, and the
// foot the frame's lowest body, within 5 mm of `lowest` (each frame's LowestGeomPoint, which the
// caller has already measured; a crawl's knees carry it). Needs the kinematics.
std::vector<bool> StanceFrames(const HumanoidSpec& spec, const MotionClip& clip, const std::vector<double>& floor,
                               const std::vector<double>& lowest, const StanceFeetOptions& options = {});

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_STANCE_FEET_H_
