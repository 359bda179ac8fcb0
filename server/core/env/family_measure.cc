#include "server/core/env/family_measure.h"

#include <algorithm>

#include "absl/strings/match.h"

namespace modskill {
namespace {

constexpr double kAirborneMargin = 0.03;  // m above a foot's first-frame height

}  // namespace

FamilyMotionMeter::FamilyMotionMeter(const HumanoidSpec& spec, double control_dt)
    : feet_(FootBodies(spec)), control_dt_(control_dt) {
  effectors_ = feet_;
  for (int b = 0; b < spec.num_bodies(); ++b) {
    const std::string& name = spec.body(b).name;
    if (absl::StrContains(name, "Wrist") || absl::StrContains(name, "Hand")) effectors_.push_back(b);
  }
}

void FamilyMotionMeter::Observe(const HumanoidState& sim) {
  if (first_) {
    for (int foot : feet_) foot_ground_.push_back(sim.body_pos[foot].z() + kAirborneMargin);
    measures_.apex_height = sim.body_pos[0].z();
    first_ = false;
  }
  measures_.apex_height = std::max(measures_.apex_height, sim.body_pos[0].z());
  for (int e : effectors_) measures_.highest_effector = std::max(measures_.highest_effector, sim.body_pos[e].z());
  bool airborne = !feet_.empty();
  for (size_t f = 0; f < feet_.size(); ++f) airborne &= sim.body_pos[feet_[f]].z() > foot_ground_[f];
  if (airborne) measures_.flight_s += control_dt_;
}

}  // namespace modskill
