#include "server/core/env/fall_detection.h"

#include <algorithm>

#include "server/core/sim/humanoid_spec.h"

namespace modskill {

FallDetector::FallDetector(const HumanoidModel& humanoid) {
  const mjModel* model = humanoid.model();
  floor_geom_ = mj_name2id(model, mjOBJ_GEOM, "floor");
  may_touch_floor_.assign(model->ngeom, 0);
  const std::vector<int> feet = FootBodies(humanoid.spec());
  for (int g = 0; g < model->ngeom; ++g) {
    const int body = model->geom_bodyid[g];
    // The world, the feet and anything that is not the humanoid (a task's objects) may.
    may_touch_floor_[g] = body == 0 || body > humanoid.num_bodies() || std::any_of(feet.begin(), feet.end(), [&](int foot) {
                            return humanoid.mj_body_id(foot) == body;
                          });
  }
}

bool FallDetector::Fallen(const mjData* data, const HumanoidState& sim) const {
  if (sim.body_pos[0].z() < kMinRootHeight) return true;
  for (int c = 0; c < data->ncon; ++c) {
    const mjContact& contact = data->contact[c];
    const int other = contact.geom1 == floor_geom_ ? contact.geom2 : contact.geom2 == floor_geom_ ? contact.geom1 : -1;
    if (other >= 0 && !may_touch_floor_[other]) return true;
  }
  return false;
}

}  // namespace modskill
