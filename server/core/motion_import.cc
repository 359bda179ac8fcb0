#include "server/core/motion_import.h"

#include <cmath>
#include <filesystem>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "server/core/clip_file.h"

namespace modskill {

std::string DefaultClipName(const std::string& path) {
  const std::filesystem::path p(path);
  const std::string stem = p.stem().string();
  const std::string extension = absl::AsciiStrToLower(p.extension().string());
  if (extension == ".txt" && absl::StartsWith(stem, "humanoid3d_")) {
    return absl::StrCat("deepmimic_", stem.substr(std::string("humanoid3d_").size()));
  }
  if (extension == ".bvh") return absl::StrCat("cmu_", stem);
  return stem;
}

absl::StatusOr<MotionClip> ImportMotionFile(const std::string& path, const HumanoidSpec& spec,
                                            const ImportOptions& options) {
  if (!(options.target_fps > 0 && options.target_fps <= 1000)) {
    return absl::InvalidArgumentError(absl::StrCat("target_fps: ", options.target_fps, " outside (0, 1000]"));
  }
  const std::string extension = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  absl::StatusOr<MotionClip> clip;
  if (extension == ".npz") {
    clip = ImportAmassNpz(path, spec);
  } else if (extension == ".bvh") {
    clip = ImportCmuBvh(path, spec);
  } else if (extension == ".txt" || extension == ".json") {
    clip = ImportDeepMimic(path, spec);
  } else if (extension == kClipFileExtension) {
    clip = ReadClipFile(path, spec);
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
  if (auto status = ValidateClip(*clip); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
  }
  MotionClip resampled = std::abs(clip->fps - options.target_fps) < 1e-9 ? *std::move(clip)
                                                                          : ResampleClip(*clip, options.target_fps);
  const absl::Status status = options.place_on_ground && !is_native ? PlaceOnGround(spec, &resampled)
                                                                     : ComputeClipKinematics(spec, &resampled);
  if (!status.ok()) return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
  return resampled;
}

}  // namespace modskill
