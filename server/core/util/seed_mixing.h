// SplitMix64's finalizer: turns related seeds (a batch seed + env index, a session seed + clip
// and round) into decorrelated ones, identically on every platform and standard library.
#ifndef MODSKILL_SERVER_CORE_UTIL_SEED_MIXING_H_
#define MODSKILL_SERVER_CORE_UTIL_SEED_MIXING_H_

#include <cstdint>

namespace modskill {

inline uint64_t MixSeed(uint64_t x) {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_UTIL_SEED_MIXING_H_
