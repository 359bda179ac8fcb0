#include "server/core/curriculum/session_motion_set.h"

#include <algorithm>
#include <numeric>

#include "absl/strings/str_cat.h"
#include "server/core/util/seed_mixing.h"

namespace modskill {

absl::Status ValidateGenerationOptions(const GenerationOptions& options) {
  if (options.variants_per_round < 1 || options.variants_per_round > 64) {
    return absl::InvalidArgumentError(
        absl::StrCat("--variants_per_failure: ", options.variants_per_round, " outside [1, 64]"));
  }
  if (options.max_generated_clips < -1 || options.max_generated_clips > 100000) {
    return absl::InvalidArgumentError(
        absl::StrCat("--max_generated_clips: ", options.max_generated_clips, " outside [-1, 100000]"));
  }
  if (options.failures_per_round < 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("--failures_per_round: ", options.failures_per_round, " must be >= 1"));
  }
  return absl::OkStatus();
}

SessionMotionSet::SessionMotionSet(std::shared_ptr<const MotionLibrary> originals, std::vector<std::string> part_names,
                                   const GenerationOptions& options, uint64_t seed)
    : options_(options),
      seed_(seed),
      num_originals_(originals->size()),
      part_names_(std::move(part_names)),
      library_(std::move(originals)) {
  if (options_.max_generated_clips < 0) options_.max_generated_clips = num_originals_;
  for (int c = 0; c < num_originals_; ++c) {
    slots_.push_back(SessionClipInfo{c, library_->clip(c).name, std::nullopt});
    added_order_.push_back(0);
    clip_ids_.push_back(c);
    slot_by_name_[library_->clip(c).name] = c;
  }
  next_id_ = num_originals_;
}

int SessionMotionSet::Find(absl::string_view name) const {
  auto it = slot_by_name_.find(name);
  return it == slot_by_name_.end() ? -1 : it->second;
}

std::vector<GenerationRequest> SessionMotionSet::PlanRounds(const std::vector<FailureReport>& failures) {
  std::vector<GenerationRequest> rounds;
  if (!options_.enabled || options_.max_generated_clips == 0) return rounds;
  const int parts = static_cast<int>(part_names_.size());
  for (const FailureReport& failure : failures) {
    if (failure.slot < 0 || failure.slot >= num_originals_) continue;
    ParentState& parent = parents_[failure.slot];
    ++parent.failures_since_round;
    if (static_cast<int>(failure.part_errors.size()) == parts) {
      parent.part_error_sum.resize(parts, 0.0);
      for (int p = 0; p < parts; ++p) parent.part_error_sum[p] += failure.part_errors[p];
      ++parent.part_error_reports;
    }
    if (parent.in_flight || parent.failures_since_round < options_.failures_per_round) continue;
    GenerationRequest request;
    request.parent = library_->shared_clip(failure.slot);
    request.count = options_.variants_per_round;
    request.seed = MixSeed(seed_ ^ MixSeed(static_cast<uint64_t>(failure.slot) << 20 ^ static_cast<uint64_t>(parent.rounds)));
    // Even rounds are part-level on the worst part when part errors are known, odd ones whole body.
    if (parent.rounds % 2 == 0 && parts > 1 && parent.part_error_reports > 0) {
      request.part = static_cast<int>(std::max_element(parent.part_error_sum.begin(), parent.part_error_sum.end()) -
                                      parent.part_error_sum.begin());
    }
    parent.part_error_sum.assign(parts, 0.0);
    parent.part_error_reports = 0;
    parent.failures_since_round = 0;
    parent.in_flight = true;
    ++parent.rounds;
    rounds.push_back(std::move(request));
  }
  return rounds;
}

MotionSetChange SessionMotionSet::Commit(const std::string& parent, std::vector<MotionVariant> variants,
                                         const std::vector<double>& weights) {
  MotionSetChange change;
  if (const int parent_slot = Find(parent); parent_slot >= 0 && parent_slot < num_originals_) {
    parents_[parent_slot].in_flight = false;
  }
  if (variants.empty()) return change;  // a round with nothing accepted changes nothing
  if (static_cast<int>(variants.size()) > options_.max_generated_clips) variants.resize(options_.max_generated_clips);
  const int overflow = live_generated() + static_cast<int>(variants.size()) - options_.max_generated_clips;
  std::vector<bool> evict(slots_.size(), false);
  if (overflow > 0) {
    std::vector<int> candidates;
    for (int s = num_originals_; s < size(); ++s) candidates.push_back(s);
    const bool have_weights = weights.size() == slots_.size();
    std::stable_sort(candidates.begin(), candidates.end(), [&](int a, int b) {
      if (have_weights && weights[a] != weights[b]) return weights[a] < weights[b];
      return added_order_[a] < added_order_[b];
    });
    for (int k = 0; k < overflow && k < static_cast<int>(candidates.size()); ++k) evict[candidates[k]] = true;
  }
  std::vector<SessionClipInfo> slots;
  std::vector<std::shared_ptr<const MotionClip>> clips;
  std::vector<int64_t> added_order;
  for (int s = 0; s < size(); ++s) {
    if (evict[s]) {
      change.removed_ids.push_back(slots_[s].id);
      evicted_names_.insert(slots_[s].name);
      continue;
    }
    change.previous_slot.push_back(s);
    slots.push_back(std::move(slots_[s]));
    clips.push_back(library_->shared_clip(s));
    added_order.push_back(added_order_[s]);
  }
  ++commits_;
  for (MotionVariant& variant : variants) {
    const int id = next_id_++;
    const int part = variant.provenance.part;
    variant.clip.name = absl::StrCat(parent, "~",
                                     part >= 0 && part < static_cast<int>(part_names_.size()) ? part_names_[part] : "w",
                                     "~", id);
    SessionClipInfo info{id, variant.clip.name, variant.provenance};
    change.previous_slot.push_back(-1);
    change.added.push_back(info);
    slots.push_back(std::move(info));
    clips.push_back(std::make_shared<const MotionClip>(std::move(variant.clip)));
    added_order.push_back(commits_);
  }
  slots_ = std::move(slots);
  added_order_ = std::move(added_order);
  Rebuild(clips);
  return change;
}

void SessionMotionSet::Rebuild(const std::vector<std::shared_ptr<const MotionClip>>& clips) {
  auto library = std::make_shared<MotionLibrary>();
  clip_ids_.clear();
  slot_by_name_.clear();
  for (size_t s = 0; s < slots_.size(); ++s) {
    // Names are unique by construction (originals are unique; generated ones carry their id).
    library->AddShared(clips[s]).IgnoreError();
    clip_ids_.push_back(slots_[s].id);
    slot_by_name_[slots_[s].name] = static_cast<int>(s);
  }
  library_ = std::move(library);
}

}  // namespace modskill
