// The clips one simulation session trains on when generative resampling is on (ModSkill's
// active skill learning, docs/DESIGN.md section 3): the session's original clips, which never leave,
// plus generated variants of the clips it fails on, each with its provenance, under a cap.
//
// Three numbers per clip, which must not be confused:
//   slot: its index in the current library (what the ClipSampler, FailureLedger and
//         AdaptiveSampler index); slots move when clips join or leave.
//   id:   what step results report (clip_id); assigned once, never reused, so an episode that
//         began on an evicted clip still names it correctly.
//   name: unique in the session; failure reports use names.
//
// When rounds happen: every terminated report on an original clip counts toward its next round;
// once `failures_per_round` have accumulated (and no round for it is in flight) PlanRounds asks
// for `variants_per_round` new clips. Rounds alternate between a whole-body round and a
// part-level round on the part with the largest mean error in the failure reports (when the
// reports carried part errors and the layout has more than one part), starting part-level.
// Eviction: when the cap would be exceeded the generated clips with the lowest sampling weight
// (the ones the policy now tracks) leave first; on equal weight, the oldest.
//
// Pure bookkeeping, not thread safe: the owner serializes calls (the session's mutex).
#ifndef MODSKILL_SERVER_CORE_CURRICULUM_SESSION_MOTION_SET_H_
#define MODSKILL_SERVER_CORE_CURRICULUM_SESSION_MOTION_SET_H_

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/curriculum/motion_variants.h"
#include "server/core/motion/motion_library.h"

namespace modskill {

struct GenerationOptions {
  bool enabled = true;          // false: the --no_generative ablation; PlanRounds never asks
  int variants_per_round = 3;   // N in ModSkill, [1, 64]
  // Live generated clips per session, [0, 100000]; -1: as many as the session has original clips,
  // so that the original motions keep at least half of the clips however small the library.
  int max_generated_clips = -1;
  int failures_per_round = 200; // terminated reports on a clip between two of its rounds, >= 1
};

// Checks the ranges above; messages name the server flag.
absl::Status ValidateGenerationOptions(const GenerationOptions& options);

// One round to run: `count` new clips from `parent`, whole body (part -1) or one part.
struct GenerationRequest {
  std::shared_ptr<const MotionClip> parent;
  int part = -1;
  uint64_t seed = 0;
  int count = 0;
};

struct SessionClipInfo {
  int id = -1;
  std::string name;
  std::optional<VariantProvenance> provenance;  // generated clips only
};

// What a commit changed. previous_slot[s]: the slot new slot s had before (-1: new clip).
struct MotionSetChange {
  std::vector<int> previous_slot;
  std::vector<SessionClipInfo> added;
  std::vector<int> removed_ids;
};

class SessionMotionSet {
 public:
  // `originals`: the session's clips (slots and ids 0 .. n-1); `part_names`: the session's
  // layout (for names and part-level rounds). `seed`: the session's seed, mixed into every
  // round's seed so that two sessions make different variants.
  SessionMotionSet(std::shared_ptr<const MotionLibrary> originals, std::vector<std::string> part_names,
                   const GenerationOptions& options, uint64_t seed);

  const GenerationOptions& options() const { return options_; }  // max_generated_clips resolved
  int size() const { return library_->size(); }
  std::shared_ptr<const MotionLibrary> library() const { return library_; }
  // Slot -> id (see EnvContext::clip_ids).
  const std::vector<int>& clip_ids() const { return clip_ids_; }
  const SessionClipInfo& info(int slot) const { return slots_[slot]; }
  int live_generated() const { return size() - num_originals_; }
  // The slot of a clip now in the set; -1 otherwise.
  int Find(absl::string_view name) const;
  // A generated clip that has been evicted (reports on it are stale, not errors).
  bool WasEvicted(absl::string_view name) const { return evicted_names_.count(name) > 0; }
  const std::vector<std::string>& part_names() const { return part_names_; }

  // Counts the terminated reports (slot, part errors or empty) of one ReportFailures call and
  // returns the rounds now due. Reports on generated clips only move the sampler: variants are
  // made from original clips, so that errors do not compound.
  struct FailureReport {
    int slot = -1;
    std::vector<float> part_errors;
  };
  std::vector<GenerationRequest> PlanRounds(const std::vector<FailureReport>& failures);

  // Adds a round's accepted clips (renamed "<parent>~<part or w>~<n>" with a session-wide n),
  // evicting generated clips by `weights` (one per current slot) to stay under the cap, and ends
  // the parent's round (also with no clips: a round whose clips were all rejected).
  MotionSetChange Commit(const std::string& parent, std::vector<MotionVariant> variants,
                         const std::vector<double>& weights);

 private:
  struct ParentState {
    int failures_since_round = 0;
    int rounds = 0;
    bool in_flight = false;
    std::vector<double> part_error_sum;
    int part_error_reports = 0;
  };

  // The library and indexes for slots_, whose clips are `clips` (by slot).
  void Rebuild(const std::vector<std::shared_ptr<const MotionClip>>& clips);

  GenerationOptions options_;
  uint64_t seed_;
  int num_originals_;
  std::vector<std::string> part_names_;
  std::vector<SessionClipInfo> slots_;
  std::vector<int64_t> added_order_;  // by slot: when it joined (originals 0)
  std::vector<int> clip_ids_;         // by slot: slots_[s].id, in the form EnvBatch takes
  std::map<std::string, int, std::less<>> slot_by_name_;
  std::set<std::string, std::less<>> evicted_names_;
  std::map<int, ParentState> parents_;  // by original slot
  std::shared_ptr<const MotionLibrary> library_;  // the clips, by slot
  int next_id_ = 0;
  int64_t commits_ = 0;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_CURRICULUM_SESSION_MOTION_SET_H_
