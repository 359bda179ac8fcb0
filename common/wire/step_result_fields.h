// The per-env fields of a step result, listed once. The server's batch buffers (BatchBuffers),
// their encoding into v1::StepResult (FillStepResult) and the client's check of what arrives
// (CheckStepResult) are all generated from this table, so a field added here and in the proto
// reaches every C++ side; tests/python/test_client.py holds Python's StepResult to the proto.
//
//   X(name, element type, wire dtype, width, value after Allocate, presence)
// name is the proto field and the BatchBuffers member; width is a StepResultWidths member
// (`vector` for a row of one value, shape [N]; otherwise [N, width]); presence says when the
// field is on the wire: kAlways, kWhenRequested (amp_obs: the session's AmpObsMode may thin it
// to the newest frame or omit it), kOptional (a server may leave it out) or kFamily (sent in
// motor-skill family sessions only, where widths.family_params > 0).
#ifndef MODSKILL_COMMON_WIRE_STEP_RESULT_FIELDS_H_
#define MODSKILL_COMMON_WIRE_STEP_RESULT_FIELDS_H_

#include <cstdint>

#define MODSKILL_STEP_RESULT_FIELDS(X)                                                                        \
  X(obs, float, FLOAT32, obs, 0, kAlways)                        /* part p: obs[part_obs[p].start ...] */     \
  X(amp_obs, float, FLOAT32, amp_obs, 0, kWhenRequested)         /* newest frame first */                     \
  X(reward, float, FLOAT32, vector, 0, kAlways)                                                               \
  X(reward_terms, float, FLOAT32, reward_terms, 0, kAlways)                                                   \
  X(done, uint8_t, UINT8, vector, 0, kAlways)                    /* ended; the row holds the next episode */  \
  X(truncated, uint8_t, UINT8, vector, 0, kAlways)               /* ended by the clip's end or step limit */  \
  X(clip_id, int32_t, INT32, vector, 0, kAlways)                 /* clip the row's obs refers to */           \
  X(frame, int32_t, INT32, vector, 0, kAlways)                   /* reference frame of the row's state */     \
  X(ended_clip_id, int32_t, INT32, vector, -1, kAlways)          /* valid where done */                       \
  X(ended_frame, int32_t, INT32, vector, -1, kAlways)                                                         \
  X(max_body_error, float, FLOAT32, vector, 0, kAlways)          /* m, before any reset */                    \
  X(mean_body_error, float, FLOAT32, vector, 0, kAlways)         /* m */                                      \
  X(part_error, float, FLOAT32, parts, 0, kOptional)             /* m per part, layout order */              \
  X(family_params, float, FLOAT32, family_params, 0, kFamily)    /* a of the row's episode */               \
  X(ended_family_params, float, FLOAT32, family_params, 0, kFamily) /* valid where done */                  \
  X(phase_step, float, FLOAT32, vector, 0, kFamily)              /* frames the phase advanced */            \
  X(spike_reward, float, FLOAT32, vector, 0, kFamily)            /* one-off part of reward */               \
  X(fitness, float, FLOAT32, vector, 0, kFamily)                 /* F of the ended episode */                \
  X(end_cause, uint8_t, UINT8, vector, 0, kOptional)             /* v1::EndCause, valid where done */

namespace modskill {

enum class StepResultPresence { kAlways, kWhenRequested, kOptional, kFamily };

// The widths of a session's per-env fields; `vector` marks a field of one value per env.
struct StepResultWidths {
  static constexpr int64_t kVector = -2;  // not -1: that is tensor_codec.h's kAnySize
  int64_t vector = kVector;
  int64_t obs = 0;
  int64_t amp_obs = 0;
  int64_t reward_terms = 0;
  int64_t parts = 0;
  int64_t family_params = 0;  // 0 outside a family session
};

}  // namespace modskill

#endif  // MODSKILL_COMMON_WIRE_STEP_RESULT_FIELDS_H_
