// The server's motion library, versioned: sessions take a snapshot when they open, uploads
// publish a new version, so adding clips never disturbs a running session.
#ifndef MODSKILL_SERVER_SERVICE_MOTION_STORE_H_
#define MODSKILL_SERVER_SERVICE_MOTION_STORE_H_

#include <memory>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/synchronization/mutex.h"
#include "server/core/motion/motion_library.h"

namespace modskill {

class MotionStore {
 public:
  explicit MotionStore(std::shared_ptr<const MotionLibrary> initial) : current_(std::move(initial)) {}

  std::shared_ptr<const MotionLibrary> Snapshot() const {
    absl::MutexLock lock(&mutex_);
    return current_;
  }

  // All or nothing: a duplicate name, or more clips in all than `max_clips`, rejects the batch.
  absl::Status Add(std::vector<MotionClip> clips, int max_clips) {
    absl::MutexLock lock(&mutex_);
    if (current_->size() + static_cast<int64_t>(clips.size()) > max_clips) {
      return absl::ResourceExhaustedError(absl::StrCat("uploads: ", clips.size(), " clips would take the library past ",
                                                       max_clips, " (--max_library_clips; it holds ",
                                                       current_->size(), ")"));
    }
    auto next = std::make_shared<MotionLibrary>(*current_);
    for (MotionClip& clip : clips) {
      if (auto status = next->Add(std::move(clip)); !status.ok()) return status;
    }
    current_ = std::move(next);
    return absl::OkStatus();
  }

 private:
  mutable absl::Mutex mutex_;
  std::shared_ptr<const MotionLibrary> current_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_MOTION_STORE_H_
