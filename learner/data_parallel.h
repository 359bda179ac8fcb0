// Data-parallel learners (DD-PPO, Wijmans et al. 2020): N learner processes, each driving its own
// servers, take the same optimizer step every minibatch because they average their gradients
// first. This is the group they form: a c10d TCPStore hosted by rank 0 at the rendezvous address
// (configuration exchange, progress marks, error messages) and a Gloo process group over it (the
// collectives). Every wait is bounded; a failure names the rank that caused it when it can.
#ifndef MODSKILL_LEARNER_DATA_PARALLEL_H_
#define MODSKILL_LEARNER_DATA_PARALLEL_H_

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <torch/torch.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "learner/data_parallel_options.h"
#include "learner/running_mean_std.h"

namespace c10d {
class Store;
class ProcessGroupGloo;
}  // namespace c10d

namespace modskill::learner {

// One setting every rank must share: its flag's name and its value as text.
using SharedSetting = std::pair<std::string, std::string>;

class DataParallel {
 public:
  // Forms the group: rank 0 hosts the store, every rank connects (retrying until the rendezvous
  // timeout) and waits for all the others. UNAVAILABLE naming the rendezvous address, and the
  // ranks that did not join, when the group is not complete in time.
  static absl::StatusOr<std::unique_ptr<DataParallel>> Join(const DataParallelOptions& options);
  ~DataParallel();

  int rank() const { return options_.rank; }
  int world_size() const { return options_.world_size; }
  const DataParallelOptions& options() const { return options_; }

  // Every rank posts `settings` under `stage` and compares them with every other rank's:
  // FAILED_PRECONDITION naming the first setting that differs and the ranks' values, on every
  // rank. Bounded by the rendezvous timeout; a rank that reported a failure is named.
  // `timeout_s`: how long ranks may take to get there (with servers to wait for, longer than
  // the rendezvous timeout).
  absl::Status CheckSettingsAgree(const std::string& stage, const std::vector<SharedSetting>& settings,
                                  double timeout_s);

  // Averages the gradients of `params` over the ranks, in place (undefined gradients count as
  // zeros and stay undefined). `finite`: this rank's loss was finite (its gradients are then
  // ignored, as zeros). Returns whether every rank's was: when not, every rank skips the step.
  absl::StatusOr<bool> AverageGradients(const std::vector<torch::Tensor>& params, bool finite);

  // Merges every rank's `batch` ([B, D], B may differ and be 0) into `stats` exactly as if the
  // concatenation of all batches had been merged, leaving identical statistics on every rank.
  absl::Status MergeRunningStats(RunningMeanStdImpl& stats, const torch::Tensor& batch);

  // Rank 0's `bytes` replace every other rank's.
  absl::Status Broadcast(std::string* bytes);

  // Element-wise sums of `values` over the ranks, in place.
  absl::Status AllReduceSum(std::vector<double>* values);
  // The smallest of the ranks' `value`.
  absl::StatusOr<double> AllReduceMin(double value);

  // Marks this rank's progress in the store, so that a failed collective can name the rank that
  // stopped answering.
  void MarkIteration(int iteration);
  // Posts this rank's fatal error for the others to name. Rank 0, which hosts the store, then
  // waits a few seconds for the others to read it.
  void ReportFailure(const absl::Status& status);

  // Seconds spent in, and bytes sent into, collectives so far (gradients, statistics, state).
  double collective_seconds() const { return collective_seconds_; }
  int64_t collective_bytes() const { return collective_bytes_; }

 private:
  DataParallel(const DataParallelOptions& options, c10::intrusive_ptr<c10d::Store> store);
  // Posts `stage`/<rank> = `value` and waits until every rank did, polling for failures.
  absl::Status PostAndWait(const std::string& stage, const std::string& value, double timeout_s);
  // Runs one collective (timed, its bytes counted); on failure, an error naming the operation and
  // what the store says about the other ranks.
  absl::Status Run(const char* operation, const std::function<void()>& collective, int64_t bytes);
  absl::Status AllReduce(std::vector<at::Tensor>& tensors, bool minimum, const char* operation);
  // Which ranks failed or fell behind, from the store (best effort, bounded).
  std::string DiagnoseOthers();

  DataParallelOptions options_;
  c10::intrusive_ptr<c10d::Store> store_;
  c10::intrusive_ptr<c10d::ProcessGroupGloo> group_;
  int iteration_ = -1;
  double collective_seconds_ = 0;
  int64_t collective_bytes_ = 0;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_DATA_PARALLEL_H_
