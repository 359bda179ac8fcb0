#include "server/core/motion/motion_library.h"

#include <algorithm>
#include <filesystem>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "server/core/motion/clip_file.h"
#include "server/core/util/data_paths.h"

namespace modskill {

absl::StatusOr<MotionLibrary> MotionLibrary::LoadDirectory(const std::string& directory, const HumanoidSpec& spec) {
  std::error_code error;
  if (!std::filesystem::is_directory(directory, error)) {
    return absl::NotFoundError(absl::StrCat(directory, ": not a motion directory"));
  }
  std::vector<std::string> paths;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error)) {
    if (entry.is_regular_file() && entry.path().extension().string() == kClipFileExtension) paths.push_back(entry.path().string());
  }
  std::sort(paths.begin(), paths.end());
  if (paths.empty()) return absl::NotFoundError(absl::StrCat(directory, ": no ", kClipFileExtension, " files"));
  MotionLibrary library;
  for (const std::string& path : paths) {
    auto clip = ReadClipFile(path, spec);
    if (!clip.ok()) return clip.status();
    if (auto status = library.Add(*std::move(clip)); !status.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
    }
  }
  return library;
}

absl::StatusOr<MotionLibrary> MotionLibrary::LoadDefault(const HumanoidSpec& spec) {
  return LoadDirectory(DataPath("motions"), spec);
}

absl::Status MotionLibrary::Add(MotionClip clip) { return AddShared(std::make_shared<const MotionClip>(std::move(clip))); }

absl::Status MotionLibrary::AddShared(std::shared_ptr<const MotionClip> clip) {
  if (clip->name.empty()) return absl::InvalidArgumentError("clip name is empty");
  if (Find(clip->name) >= 0) return absl::AlreadyExistsError(absl::StrCat("clip '", clip->name, "' already in the library"));
  if (clip->body_pos.size() != static_cast<size_t>(clip->num_frames) * clip->num_bodies) {
    return absl::FailedPreconditionError(absl::StrCat("clip '", clip->name, "' has no kinematics computed"));
  }
  clips_.push_back(std::move(clip));
  return absl::OkStatus();
}

int MotionLibrary::Find(absl::string_view name) const {
  for (int i = 0; i < size(); ++i) {
    if (clips_[i]->name == name) return i;
  }
  return -1;
}

absl::StatusOr<MotionLibrary> MotionLibrary::Subset(const std::vector<std::string>& names) const {
  MotionLibrary subset;
  for (const std::string& name : names) {
    const int id = Find(name);
    if (id < 0) return absl::NotFoundError(absl::StrCat("motion subset: unknown clip '", name, "'"));
    if (subset.Find(name) < 0) subset.clips_.push_back(clips_[id]);
  }
  if (subset.clips_.empty()) return absl::InvalidArgumentError("motion subset: empty");
  return subset;
}

double MotionLibrary::TotalDuration() const {
  double total = 0;
  for (const auto& clip : clips_) total += clip->duration();
  return total;
}

}  // namespace modskill
