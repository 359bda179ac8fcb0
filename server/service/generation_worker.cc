#include "server/service/generation_worker.h"

#include <filesystem>

#include "absl/strings/str_cat.h"
#include "common/log.h"
#include "server/core/motion/clip_file.h"
#include "server/core/motion/clip_name.h"
#include "server/core/util/confined_path.h"
#include "server/service/discriminator_scorer.h"

namespace modskill {
namespace {

constexpr int kDiscriminatorFrames = 30;

}  // namespace

GenerationWorker::GenerationWorker(const HumanoidSpec* spec, std::unique_ptr<ExternalMotionGenerator> external,
                                   const PlausibilityOptions& filter, std::string save_dir, int64_t max_saved,
                                   int max_queued)
    : spec_(spec),
      external_(std::move(external)),
      filter_(filter),
      save_dir_(std::move(save_dir)),
      max_saved_(max_saved),
      max_queued_(max_queued) {
  thread_ = std::thread([this] { Run(); });
}

GenerationWorker::~GenerationWorker() {
  {
    absl::MutexLock lock(&mutex_);
    stopping_ = true;
  }
  thread_.join();
}

void GenerationWorker::Enqueue(const std::shared_ptr<SimulationSession>& session,
                               std::vector<GenerationRequest> rounds) {
  std::vector<std::string> dropped;
  {
    absl::MutexLock lock(&mutex_);
    for (GenerationRequest& request : rounds) {
      if (static_cast<int>(queue_.size()) >= max_queued_ || stopping_) {
        dropped.push_back(request.parent->name);
        continue;
      }
      queue_.push_back(Job{session, std::move(request)});
    }
  }
  for (const std::string& parent : dropped) session->AbandonRound(parent);
}

void GenerationWorker::WaitIdle() {
  absl::MutexLock lock(&mutex_);
  auto idle = [this]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_) { return queue_.empty() && !busy_; };
  mutex_.Await(absl::Condition(&idle));
}

void GenerationWorker::Run() {
  for (;;) {
    Job job;
    {
      absl::MutexLock lock(&mutex_);
      auto ready = [this]() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mutex_) { return stopping_ || !queue_.empty(); };
      mutex_.Await(absl::Condition(&ready));
      if (stopping_) return;
      job = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    // A session that closed meanwhile needs nothing more.
    if (std::shared_ptr<SimulationSession> session = job.session.lock()) RunRound(*session, job.request);
    absl::MutexLock lock(&mutex_);
    busy_ = false;
  }
}

void GenerationWorker::RunRound(SimulationSession& session, const GenerationRequest& request) {
  GenerationCounters counters;
  std::vector<MotionVariant> candidates = GenerateCandidates(session, request, counters);
  std::vector<MotionVariant> accepted = FilterCandidates(session, request, std::move(candidates), counters);
  const std::vector<std::shared_ptr<const MotionClip>> added =
      session.CommitRound(request.parent->name, std::move(accepted), counters);
  if (save_dir_.empty()) return;
  SaveGenerated(session, added);
}

std::vector<MotionVariant> GenerationWorker::GenerateCandidates(SimulationSession& session,
                                                                const GenerationRequest& request,
                                                                GenerationCounters& counters) {
  const PartLayout& layout = session.batch->spec().layout;
  const MotionClip& parent = *request.parent;
  absl::StatusOr<std::vector<MotionVariant>> candidates = absl::UnavailableError("no external generator");
  if (external_ != nullptr) {
    candidates = external_->Generate(*spec_, layout, parent, request.part, request.seed, request.count);
    if (!candidates.ok()) {
      ++counters.generator_errors;
      counters.last_generator_error = std::string(candidates.status().message());
      ++counters.builtin_fallbacks;
      LogLine("session %s: generator %s failed for '%s' (%s); using the built-in generator", session.id,
              external_->address(), parent.name, candidates.status().ToString());
    }
  }
  if (!candidates.ok()) {
    VariantOptions options;
    options.count = request.count;
    options.part = request.part;
    options.seed = request.seed;
    candidates = GenerateVariants(*spec_, layout, parent, options);
    if (!candidates.ok()) {
      LogLine("session %s: built-in generator failed for '%s': %s", session.id, parent.name,
              candidates.status().ToString());
      candidates = std::vector<MotionVariant>();
    }
  }
  return *std::move(candidates);
}

std::vector<MotionVariant> GenerationWorker::FilterCandidates(SimulationSession& session,
                                                              const GenerationRequest& request,
                                                              std::vector<MotionVariant> candidates,
                                                              GenerationCounters& counters) {
  // With the learner's discriminator, ModSkill's rule too: a mean score >= 0.5 on 30 random frames.
  const std::shared_ptr<const DiscriminatorScorer> discriminator = session.discriminator();
  std::vector<MotionVariant> accepted;
  for (size_t k = 0; k < candidates.size(); ++k) {
    MotionVariant& variant = candidates[k];
    std::vector<float> scores;
    if (discriminator != nullptr) {
      auto scored = discriminator->ScoreClip(session.batch->spec(), variant.clip, kDiscriminatorFrames,
                                             request.seed + k);
      if (scored.ok()) {
        scores = *std::move(scored);
      } else {
        LogLine("session %s: could not score '%s': %s", session.id, variant.clip.name, scored.status().ToString());
      }
    }
    // A failed scoring leaves `scores` empty, which the discriminator check rejects.
    const PlausibilityVerdict verdict = CheckVariantPlausibility(*spec_, variant.clip, *request.parent, filter_,
                                                                 discriminator != nullptr ? &scores : nullptr);
    if (verdict.accepted) {
      accepted.push_back(std::move(variant));
      continue;
    }
    ++counters.rejected;
    ++counters.rejected_by_check[verdict.reason.substr(0, verdict.reason.find(':'))];
  }
  return accepted;
}

void GenerationWorker::SaveGenerated(const SimulationSession& session,
                                     const std::vector<std::shared_ptr<const MotionClip>>& added) {
  for (const auto& clip : added) {
    if (saved_ >= max_saved_) {
      if (saved_++ == max_saved_) {
        LogLine("--save_generated: %lld clips written, the --max_saved_generated_clips limit; saving no more",
                static_cast<long long>(max_saved_));
      }
      break;
    }
    // Names come from clients (a parent uploaded with AddMotions) and session ids from the
    // server; both are checked and the path confined to --save_generated all the same.
    auto path = [&]() -> absl::StatusOr<std::string> {
      auto directory = ConfinedPath(save_dir_, session.id);
      if (!directory.ok()) return directory.status();
      const int max_name = kMaxFileNameLength - static_cast<int>(kClipFileExtension.size());
      if (absl::Status name = ValidateClipName(clip->name, max_name); !name.ok()) return name;
      return ConfinedPath(*directory, absl::StrCat(clip->name, kClipFileExtension));
    }();
    if (!path.ok()) {
      LogLine("session %s: not saving a generated clip: %s", session.id, path.status().ToString());
      continue;
    }
    std::error_code error;
    std::filesystem::create_directories(std::filesystem::path(*path).parent_path(), error);
    if (absl::Status status = WriteClipFile(*path, *clip); !status.ok()) {
      LogLine("session %s: could not save '%s': %s", session.id, *path, status.ToString());
    } else {
      ++saved_;
    }
  }
}

}  // namespace modskill
