// Why a run's episodes ended (StepResult.end_cause): counts by v1::EndCause, for the training
// log of task runs and the task evaluation's table. Tells a fall from a task's own failure
// (strike's forbidden contact) from the time limit.
#ifndef MODSKILL_LEARNER_EPISODE_ENDS_H_
#define MODSKILL_LEARNER_EPISODE_ENDS_H_

#include <array>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::learner {

class EpisodeEnds {
 public:
  static constexpr int kCauses = v1::EndCause_MAX + 1;

  // One ended episode; a cause outside v1::EndCause counts as unspecified.
  void Add(int cause);
  void Merge(const EpisodeEnds& other);
  int count(v1::EndCause cause) const { return count_[cause]; }
  int total() const;
  // "fall 40, task 20, time 4": the causes that occurred, in EndCause order (unspecified as
  // "unreported"); "-" when no episode ended.
  std::string Summary() const;
  // The causes' short names (time, tracking, fall, task, blow_up), EndCause order from TIME on.
  static std::vector<std::string> Names();
  // Counts in Names() order.
  std::vector<int> Counts() const;

 private:
  std::array<int, kCauses> count_{};
};

// StepResult.end_cause as n values; empty when the server left the optional field out.
absl::StatusOr<std::vector<int>> ReadEndCauses(const v1::StepResult& result, int n);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_EPISODE_ENDS_H_
