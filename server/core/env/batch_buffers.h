// Preallocated batch tensors that envs write their rows into (EnvPool style): one contiguous
// block per field of common/wire/step_result_fields.h, row i belonging to env i. Shipped as is,
// never gathered.
#ifndef MODSKILL_SERVER_CORE_ENV_BATCH_BUFFERS_H_
#define MODSKILL_SERVER_CORE_ENV_BATCH_BUFFERS_H_

#include <cstdint>
#include <vector>

#include "common/wire/step_result_fields.h"
#include "server/core/env/env_spec.h"

namespace modskill {

// The widths of the step result's fields for an env of `spec`.
inline StepResultWidths WidthsOf(const EnvSpec& spec) {
  StepResultWidths widths;
  widths.obs = spec.obs_size;
  widths.amp_obs = spec.amp_obs_size;
  widths.reward_terms = static_cast<int64_t>(spec.reward_terms.size());
  widths.parts = spec.layout.num_parts();
  widths.family_params = static_cast<int64_t>(spec.family.size());
  return widths;
}

struct BatchBuffers {
  int num_envs = 0;
  StepResultWidths widths;
#define MODSKILL_BUFFER_MEMBER(name, type, dtype, width, initial, presence) std::vector<type> name;
  MODSKILL_STEP_RESULT_FIELDS(MODSKILL_BUFFER_MEMBER)
#undef MODSKILL_BUFFER_MEMBER

  void Allocate(const EnvSpec& spec, int envs) {
    num_envs = envs;
    widths = WidthsOf(spec);
#define MODSKILL_BUFFER_ALLOCATE(name, type, dtype, width, initial, presence) \
  name.assign(static_cast<size_t>(envs) * RowSize(widths.width), static_cast<type>(initial));
    MODSKILL_STEP_RESULT_FIELDS(MODSKILL_BUFFER_ALLOCATE)
#undef MODSKILL_BUFFER_ALLOCATE
  }

  // Values per env of a field of `width`.
  static size_t RowSize(int64_t width) { return width == StepResultWidths::kVector ? 1 : static_cast<size_t>(width); }
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_BATCH_BUFFERS_H_
