// Core structs -> wire messages. One direction only: the core never sees protobuf.
#ifndef MODSKILL_SERVER_SERVICE_PROTO_CONVERSIONS_H_
#define MODSKILL_SERVER_SERVICE_PROTO_CONVERSIONS_H_

#include <string>
#include <vector>

#include <grpcpp/support/status.h>

#include "absl/status/status.h"
#include "modskill/v1/modskill.pb.h"
#include "server/core/env/env_batch.h"
#include "server/core/env/rollout.h"
#include "server/service/simulation_session.h"

namespace modskill {

void ToProto(const EnvSpec& spec, const HumanoidModel& humanoid, v1::EnvSpec* out);
void ToProto(const MotionClip& clip, v1::MotionInfo* out);
void ToProto(const ClipRolloutMetrics& metrics, v1::ClipMetrics* out);
// A generated clip's origin; `part_names` names its part (layout order).
void ToProto(const std::vector<std::string>& part_names, const VariantProvenance& provenance, v1::ClipProvenance* out);
// The clips that joined and left since the stream last installed a motion set.
void ToProto(const std::vector<std::string>& part_names, const PendingMotionSet& pending, v1::MotionSetUpdate* out);

// Fills a StepResult from the batch's buffers; amp_frames = 0 leaves amp_obs empty.
void FillStepResult(const EnvBatch& batch, int64_t step, int amp_frames, v1::StepResult* out);

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_PROTO_CONVERSIONS_H_
