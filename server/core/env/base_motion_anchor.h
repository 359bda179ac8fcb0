// The base motion of a goal task (steer, reach, strike), observed as a tracker observes its
// reference. In a goal task the clip loops underneath as the base pose of residual actions, but
// the character walks wherever its goal takes it, so the clip's own world placement soon means
// nothing. Each step the next reference frame is carried by the horizontal rigid motion (a yaw
// and an xy shift) that puts the current reference frame's root on the character's root, facing
// the character's heading: the features then say "go on with the clip from where you are", which
// is what a tracker saw whenever it tracked well, and a frozen tracker's skill attention can read
// them (ModSkill's skills reused as a prior, learner/README.md).
#ifndef MODSKILL_SERVER_CORE_ENV_BASE_MOTION_ANCHOR_H_
#define MODSKILL_SERVER_CORE_ENV_BASE_MOTION_ANCHOR_H_

#include "server/core/env/humanoid_state.h"

namespace modskill {

// Moves `target` (every body's position, rotation, velocity and angular velocity) by the yaw
// rotation and horizontal shift that map `anchor`'s root onto `sim`'s root (x, y and heading;
// heights and tilts are left as the clip has them).
void AnchorToCharacter(const HumanoidState& anchor, const HumanoidState& sim, HumanoidState* target);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_BASE_MOTION_ANCHOR_H_
