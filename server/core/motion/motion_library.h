// The clips a server can sample from, shared read-only by every env.
#ifndef MODSKILL_SERVER_CORE_MOTION_MOTION_LIBRARY_H_
#define MODSKILL_SERVER_CORE_MOTION_MOTION_LIBRARY_H_

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/motion/motion_clip.h"

namespace modskill {

class MotionLibrary {
 public:
  // Loads every .msclip file of `directory` (sorted by name, so ids are stable).
  static absl::StatusOr<MotionLibrary> LoadDirectory(const std::string& directory, const HumanoidSpec& spec);
  // The library shipped in data/motions.
  static absl::StatusOr<MotionLibrary> LoadDefault(const HumanoidSpec& spec);

  // Fails on a duplicate name or a clip that does not fit the skeleton.
  absl::Status Add(MotionClip clip);
  absl::Status AddShared(std::shared_ptr<const MotionClip> clip);

  int size() const { return static_cast<int>(clips_.size()); }
  const MotionClip& clip(int id) const { return *clips_[id]; }
  std::shared_ptr<const MotionClip> shared_clip(int id) const { return clips_[id]; }
  // -1 when absent.
  int Find(absl::string_view name) const;
  // The named clips as a new library (same clip objects); errors name the unknown clip.
  absl::StatusOr<MotionLibrary> Subset(const std::vector<std::string>& names) const;
  double TotalDuration() const;

 private:
  std::vector<std::shared_ptr<const MotionClip>> clips_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_MOTION_LIBRARY_H_
