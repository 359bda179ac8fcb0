// What modskill-learner reports after each training iteration: its line on stdout, its row in
// progress.csv and in TensorBoard, the time budget, and the policy exports of the milestones it
// passed.
#ifndef MODSKILL_LEARNER_TOOLS_ITERATION_REPORT_H_
#define MODSKILL_LEARNER_TOOLS_ITERATION_REPORT_H_

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/time/time.h"
#include "learner/tensorboard_writer.h"
#include "learner/trainer.h"

namespace modskill::learner {

// The columns of progress.csv (and, from the third on, the TensorBoard scalars), in row order:
// one reward_<term> per reward term of the session (tracking: pos, rot, vel, ang_vel, energy),
// and in task runs the normalized return.
std::vector<std::string> ProgressColumns(const Trainer& trainer);

// One iteration's figures in ProgressColumns() order; `elapsed`: seconds since the run started.
std::vector<double> ProgressRow(const IterationStats& s, double elapsed, const Trainer& trainer);

// One iteration's line on stdout; `last`: the run's last iteration, `left`: the estimated
// seconds to the end of the run.
void PrintIteration(const IterationStats& s, const Trainer& trainer, int last, double left);

// Reports each iteration (the files on rank 0 only: the other ranks have no `events` and `csv`)
// and sets `*stop` once the time budget is spent.
struct IterationReporter {
  Trainer* trainer;
  TensorBoardWriter* events;
  CsvLogger* csv;
  std::vector<int64_t> milestones;  // env steps, ascending
  std::atomic<bool>* stop;
  size_t next_milestone = 0;
  absl::Time start;
  double budget_min = 0;  // 0: no budget
  int first = 0, last = 0;

  // Skips the milestones a resumed run passed already.
  void SkipPassedMilestones();
  void Report(const IterationStats& s);

 private:
  // The first iteration at or past a milestone exports the policy it ends with.
  void ExportMilestones(const IterationStats& s);
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TOOLS_ITERATION_REPORT_H_
