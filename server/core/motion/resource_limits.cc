#include "server/core/motion/resource_limits.h"

namespace modskill {
namespace {

ResourceLimits& MutableLimits() {
  static ResourceLimits limits;
  return limits;
}

}  // namespace

const ResourceLimits& DefaultResourceLimits() { return MutableLimits(); }

void SetDefaultResourceLimits(const ResourceLimits& limits) { MutableLimits() = limits; }

}  // namespace modskill
