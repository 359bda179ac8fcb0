#include "server/service/simulation_session.h"

#include "absl/strings/str_cat.h"
#include "common/shown_value.h"

namespace modskill {
namespace {

std::vector<std::string> ClipNames(const MotionLibrary& motions) {
  std::vector<std::string> names;
  for (int c = 0; c < motions.size(); ++c) names.push_back(motions.clip(c).name);
  return names;
}

}  // namespace

SimulationSession::SimulationSession(std::string session_id, std::string client, std::unique_ptr<EnvBatch> envs,
                                     SamplingScheme sampling, double sampling_floor,
                                     const GenerationOptions& generation, uint64_t seed)
    : id(std::move(session_id)),
      peer(std::move(client)),
      batch(std::move(envs)),
      clip_names(ClipNames(batch->motions())),
      opened(absl::Now()),
      motion_set(batch->shared_motions(), batch->spec().layout.PartNames(), generation, seed),
      ledger(batch->motions().size(), batch->spec().layout.num_parts()),
      adaptive_sampler(batch->motions().size(), sampling, sampling_floor),
      reference_amp_(batch->shared_reference_amp()) {}

absl::StatusOr<std::vector<GenerationRequest>> SimulationSession::RecordReports(
    const std::vector<NamedClipReport>& reports) {
  absl::MutexLock lock(&mutex);
  std::vector<FailureLedger::Report> records;
  records.reserve(reports.size());
  int64_t stale = 0;
  for (size_t r = 0; r < reports.size(); ++r) {
    FailureLedger::Report record;
    record.clip = motion_set.Find(reports[r].clip);
    if (record.clip < 0) {
      // An episode that began on a clip evicted since: nothing left to learn about it.
      if (motion_set.WasEvicted(reports[r].clip)) {
        ++stale;
        continue;
      }
      return absl::NotFoundError(
          absl::StrCat("failures[", r, "].clip: '", ShownValue(reports[r].clip), "' is not a clip of this session"));
    }
    record.frame = reports[r].frame;
    record.part_errors = reports[r].part_errors;
    record.terminated = reports[r].terminated;
    record.steps = reports[r].steps;
    records.push_back(std::move(record));
  }
  const MotionLibrary& library = *motion_set.library();
  std::vector<int> frames;
  for (int c = 0; c < library.size(); ++c) frames.push_back(library.clip(c).num_frames);
  if (absl::Status status = ledger.Record(records, frames); !status.ok()) return status;
  std::vector<SessionMotionSet::FailureReport> failures;
  for (const FailureLedger::Report& record : records) {
    adaptive_sampler.Observe(record.clip, /*failed=*/record.terminated, record.steps);
    if (record.terminated) failures.push_back({record.clip, record.part_errors});
  }
  generation.stale_reports += stale;
  std::vector<GenerationRequest> rounds = motion_set.PlanRounds(failures);
  generation.requests += static_cast<int64_t>(rounds.size());
  PublishWeights();
  return rounds;
}

std::vector<std::shared_ptr<const MotionClip>> SimulationSession::CommitRound(const std::string& parent,
                                                                              std::vector<MotionVariant> accepted,
                                                                              const GenerationCounters& counters) {
  absl::MutexLock lock(&mutex);
  generation.generated += static_cast<int64_t>(accepted.size());
  generation.rejected += counters.rejected;
  for (const auto& [check, count] : counters.rejected_by_check) generation.rejected_by_check[check] += count;
  generation.generator_errors += counters.generator_errors;
  if (!counters.last_generator_error.empty()) generation.last_generator_error = counters.last_generator_error;
  generation.builtin_fallbacks += counters.builtin_fallbacks;

  // New variants start with their parent's failure count, so they are drawn about as often.
  const int parent_slot = motion_set.Find(parent);
  const double parent_count = parent_slot >= 0 && adaptive_sampler.scheme() == SamplingScheme::kFailureCount
                                  ? adaptive_sampler.raw_weights()[parent_slot] - kFailureCountEpsilon
                                  : 0.0;
  MotionSetChange change = motion_set.Commit(parent, std::move(accepted), adaptive_sampler.raw_weights());
  if (change.added.empty() && change.removed_ids.empty()) return {};
  generation.evicted += static_cast<int64_t>(change.removed_ids.size());
  ledger.Remap(change.previous_slot);
  adaptive_sampler.Remap(change.previous_slot, parent_count);
  reference_amp_ = std::make_shared<const ReferenceAmpFrames>(batch->spec(), *motion_set.library());

  if (!pending_motion_set_.has_value()) pending_motion_set_.emplace();
  PendingMotionSet& pending = *pending_motion_set_;
  pending.library = motion_set.library();
  pending.clip_ids = motion_set.clip_ids();
  pending.reference_amp = reference_amp_;
  std::vector<std::shared_ptr<const MotionClip>> added;
  for (SessionClipInfo& info : change.added) {
    added.push_back(motion_set.library()->shared_clip(motion_set.Find(info.name)));
    pending.added.push_back(std::move(info));
  }
  for (int removed : change.removed_ids) pending.removed_ids.push_back(removed);
  PublishWeights();
  return added;
}

void SimulationSession::AbandonRound(const std::string& parent) {
  absl::MutexLock lock(&mutex);
  ++generation.dropped_requests;
  motion_set.Commit(parent, {}, adaptive_sampler.raw_weights());
}

void SimulationSession::PublishWeights() {
  pending_weights_ = adaptive_sampler.Weights();
  pending_.store(true, std::memory_order_release);
}

bool SimulationSession::TakePending(std::vector<double>* weights, std::optional<PendingMotionSet>* motion_set_out) {
  motion_set_out->reset();
  if (!pending_.load(std::memory_order_acquire)) return false;
  absl::MutexLock lock(&mutex);
  weights->swap(pending_weights_);
  motion_set_out->swap(pending_motion_set_);
  pending_motion_set_.reset();
  pending_.store(false, std::memory_order_relaxed);
  return true;
}

void SimulationSession::SetDiscriminator(std::shared_ptr<const DiscriminatorScorer> scorer) {
  absl::MutexLock lock(&mutex);
  discriminator_ = std::move(scorer);
}

std::shared_ptr<const DiscriminatorScorer> SimulationSession::discriminator() const {
  absl::MutexLock lock(&mutex);
  return discriminator_;
}

std::shared_ptr<const ReferenceAmpFrames> SimulationSession::reference_amp() const {
  absl::MutexLock lock(&mutex);
  return reference_amp_;
}

}  // namespace modskill
