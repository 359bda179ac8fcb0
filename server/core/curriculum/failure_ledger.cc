#include "server/core/curriculum/failure_ledger.h"

#include <cmath>

#include "absl/strings/str_cat.h"

namespace modskill {

FailureLedger::FailureLedger(int num_clips, int num_parts) : clips_(num_clips), num_parts_(num_parts) {
  for (ClipFailureRecord& clip : clips_) clip.mean_part_errors.assign(num_parts, 0.0);
}

absl::Status FailureLedger::Record(absl::Span<const Report> reports, absl::Span<const int> clip_frames) {
  for (size_t r = 0; r < reports.size(); ++r) {
    const Report& report = reports[r];
    const std::string where = absl::StrCat("failures[", r, "]");
    if (report.clip < 0 || report.clip >= static_cast<int>(clips_.size())) {
      return absl::NotFoundError(absl::StrCat(where, ".clip: unknown clip"));
    }
    if (report.frame < -1 || report.frame >= clip_frames[report.clip]) {
      return absl::InvalidArgumentError(absl::StrCat(where, ".frame: ", report.frame, " outside [-1, ",
                                                     clip_frames[report.clip], ")"));
    }
    if (report.steps < 0) {
      return absl::InvalidArgumentError(absl::StrCat(where, ".steps: ", report.steps, " is negative"));
    }
    if (!report.part_errors.empty() && static_cast<int>(report.part_errors.size()) != num_parts_) {
      return absl::InvalidArgumentError(absl::StrCat(where, ".part_errors: ", report.part_errors.size(),
                                                     " values, the session's layout has ", num_parts_, " parts"));
    }
    for (size_t p = 0; p < report.part_errors.size(); ++p) {
      const float e = report.part_errors[p];
      if (!std::isfinite(e) || e < 0 || e > 100) {
        return absl::InvalidArgumentError(absl::StrCat(where, ".part_errors[", p, "]: ", e, " is not in [0, 100] m"));
      }
    }
  }
  for (const Report& report : reports) {
    ClipFailureRecord& clip = clips_[report.clip];
    clip.steps += report.steps;
    if (!report.terminated) {
      ++clip.successes;
      continue;
    }
    ++clip.failures;
    clip.last_failed_frame = report.frame;
    if (!report.part_errors.empty()) {
      ++clip.part_error_reports;
      for (int p = 0; p < num_parts_; ++p) {
        clip.mean_part_errors[p] += (report.part_errors[p] - clip.mean_part_errors[p]) / clip.part_error_reports;
      }
    }
  }
  reports_ += static_cast<int64_t>(reports.size());
  return absl::OkStatus();
}

void FailureLedger::Remap(absl::Span<const int> previous) {
  std::vector<ClipFailureRecord> remapped(previous.size());
  for (size_t c = 0; c < previous.size(); ++c) {
    if (previous[c] >= 0 && previous[c] < static_cast<int>(clips_.size())) {
      remapped[c] = std::move(clips_[previous[c]]);
    } else {
      remapped[c].mean_part_errors.assign(num_parts_, 0.0);
    }
  }
  clips_ = std::move(remapped);
}

}  // namespace modskill
