// What a learner reported about each clip of a session: failures, successes, where it failed
// and by how much per body part. The sampler's weights are derived from it.
#ifndef MODSKILL_SERVER_CORE_CURRICULUM_FAILURE_LEDGER_H_
#define MODSKILL_SERVER_CORE_CURRICULUM_FAILURE_LEDGER_H_

#include <cstdint>
#include <vector>

#include "absl/status/status.h"
#include "absl/types/span.h"

namespace modskill {

struct ClipFailureRecord {
  int64_t failures = 0;
  int64_t successes = 0;
  int last_failed_frame = -1;
  int64_t steps = 0;  // sum of the reports' episode lengths (control steps; unknown ones add 0)
  std::vector<double> mean_part_errors;  // running mean over failures that carried part errors
  int64_t part_error_reports = 0;
};

class FailureLedger {
 public:
  FailureLedger(int num_clips, int num_parts);

  struct Report {
    int clip = -1;
    int frame = -1;
    std::vector<float> part_errors;  // empty or one per part, meters
    bool terminated = true;
    int steps = 0;  // control steps the episode ran; 0: unknown
  };
  // Validates every report (clip index, frame, non-negative steps, part count, finite
  // non-negative errors below 100 m) before recording any; the message names the report index
  // and field.
  absl::Status Record(absl::Span<const Report> reports, absl::Span<const int> clip_frames);

  // The clip list changed (generative resampling): new clip c was old clip previous[c], or is
  // new (-1) and starts with an empty record. Clips not named in `previous` are forgotten.
  void Remap(absl::Span<const int> previous);

  const std::vector<ClipFailureRecord>& clips() const { return clips_; }
  int64_t reports() const { return reports_; }
  int num_parts() const { return num_parts_; }

 private:
  std::vector<ClipFailureRecord> clips_;
  int num_parts_;
  int64_t reports_ = 0;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_CURRICULUM_FAILURE_LEDGER_H_
