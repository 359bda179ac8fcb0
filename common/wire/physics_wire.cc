#include "common/wire/physics_wire.h"

namespace modskill {

void ToWire(const PhysicsSettings& settings, v1::PhysicsSettings* out) {
  out->set_physics_dt(settings.physics_dt);
  out->set_pd_mode(settings.pd_mode);
  out->set_pd_gain_scale(settings.pd_gain_scale);
  out->set_damp_to_reference_rate(settings.damp_to_reference_rate);
}

PhysicsSettings PhysicsOf(const v1::EnvSpec& spec) {
  PhysicsSettings settings;
  if (!spec.has_physics()) return settings;
  settings.physics_dt = spec.physics().physics_dt();
  settings.pd_mode = spec.physics().pd_mode();
  settings.pd_gain_scale = spec.physics().pd_gain_scale();
  settings.damp_to_reference_rate = spec.physics().damp_to_reference_rate();
  return settings;
}

}  // namespace modskill
