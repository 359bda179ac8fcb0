// What a learner may assume of a step result before it reads the bytes: every per-env tensor has
// the dtype the proto documents, one row per env, the width the session's spec gives, and exactly
// as many bytes as its shape needs. A server (or a man in the middle) that sends anything else
// gets a clear error instead of an out-of-bounds read in the learner.
#ifndef MODSKILL_CLIENT_CPP_STEP_RESULT_CHECK_H_
#define MODSKILL_CLIENT_CPP_STEP_RESULT_CHECK_H_

#include "absl/status/status.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill {

// DataLoss naming the field when `result` does not fit `num_envs` envs of `spec`. amp_obs and
// part_error may be absent (amp_obs OMIT, the initial result); when present they are checked too.
absl::Status CheckStepResult(const v1::StepResult& result, int num_envs, const v1::EnvSpec& spec);

}  // namespace modskill

#endif  // MODSKILL_CLIENT_CPP_STEP_RESULT_CHECK_H_
