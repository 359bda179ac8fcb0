// PhysicsSettings (common/policy/physics_settings.h) and their proto twin, both ways.
#ifndef MODSKILL_COMMON_WIRE_PHYSICS_WIRE_H_
#define MODSKILL_COMMON_WIRE_PHYSICS_WIRE_H_

#include "common/policy/physics_settings.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

void ToWire(const PhysicsSettings& settings, v1::PhysicsSettings* out);
// A server from before the field sends none: not recorded (physics_dt 0), and nothing is compared.
PhysicsSettings PhysicsOf(const v1::EnvSpec& spec);

}  // namespace modskill

#endif  // MODSKILL_COMMON_WIRE_PHYSICS_WIRE_H_
