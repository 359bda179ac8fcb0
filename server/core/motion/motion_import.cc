#include "server/core/motion/motion_import.h"

#include <cmath>
#include <filesystem>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "server/core/motion/clip_file.h"
#include "server/core/motion/clip_name.h"

namespace modskill {

std::string DefaultClipName(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string stem = p.stem().string();
  const std::string extension = absl::AsciiStrToLower(p.extension().string());
  std::string name = stem;
  if (extension == ".txt" && absl::StartsWith(stem, "humanoid3d_")) {
    name = absl::StrCat("deepmimic_", stem.substr(std::string("humanoid3d_").size()));
  } else if (extension == ".bvh") {
    name = absl::StrCat("cmu_", stem);
  }
  return SanitizeClipName(name, DefaultResourceLimits().max_name_length);
}

absl::StatusOr<MotionClip> ImportMotionFile(const std::string& path, const HumanoidSpec& spec,
                                            const ImportOptions& options) {
  if (!(options.target_fps > 0 && options.target_fps <= 1000)) {
    return absl::InvalidArgumentError(absl::StrCat("target_fps: ", options.target_fps, " outside (0, 1000]"));
  }
  const std::string extension = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  absl::StatusOr<MotionClip> clip;
  if (extension == ".npz") {
    clip = ImportAmassNpz(path, spec, options.limits);
  } else if (extension == ".bvh") {
    clip = ImportCmuBvh(path, spec, options.limits);
  } else if (extension == ".txt" || extension == ".json") {
    clip = ImportDeepMimic(path, spec, options.limits);
  } else if (extension == kClipFileExtension) {
    clip = ReadClipFile(path, spec, options.limits);
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat(path, ": unknown motion format '", extension, "' (expected .npz, .bvh, .txt or .msclip)"));
  }
  if (!clip.ok()) return clip.status();
  const bool is_native = extension == kClipFileExtension;
  if (!is_native) clip->name = DefaultClipName(path);
  if (!options.name.empty()) clip->name = options.name;
  if (!options.label.empty()) clip->label = options.label;
  if (!options.humanml3d_id.empty()) clip->humanml3d_id = options.humanml3d_id;
  if (clip->source.empty()) clip->source = std::filesystem::path(path).filename().string();
  if (auto status = ValidateClipName(clip->name, options.limits.max_name_length); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
  }
  if (auto status = ValidateClip(*clip, options.limits); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
  }
  absl::StatusOr<MotionClip> resampled = *std::move(clip);
  if (std::abs(resampled->fps - options.target_fps) >= 1e-9) {
    resampled = ResampleClip(*resampled, options.target_fps, options.limits);
  }
  if (!resampled.ok()) return absl::InvalidArgumentError(absl::StrCat(path, ": ", resampled.status().message()));
  const absl::Status status = options.place_on_ground && !is_native ? PlaceOnGround(spec, &*resampled, options.floor)
                                                                     : ComputeClipKinematics(spec, &*resampled);
  if (!status.ok()) return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
  return *std::move(resampled);
}

}  // namespace modskill
