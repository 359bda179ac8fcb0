// Why an episode ended, as StepResult.end_cause carries it (the values are v1::EndCause's;
// server/service/proto_conversions.cc holds them equal).
#ifndef MODSKILL_SERVER_CORE_ENV_EPISODE_END_H_
#define MODSKILL_SERVER_CORE_ENV_EPISODE_END_H_

#include <cstdint>

namespace modskill {

enum class EpisodeEnd : uint8_t {
  kNone = 0,      // the episode goes on
  kTime = 1,      // the clip's end or the step limit (truncated)
  kTracking = 2,  // a body error past the termination distance
  kFall = 3,      // a goal task's fall, or a family episode's
  kTask = 4,      // a goal task's own failure (strike: a forbidden contact, the target lost)
  kBlowUp = 5,    // the physics diverged
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_EPISODE_END_H_
