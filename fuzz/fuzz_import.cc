#include "fuzz/fuzz_import.h"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "server/core/motion/clip_name.h"
#include "server/core/motion/motion_import.h"
#include "server/core/motion/resource_limits.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill::fuzz {
namespace {

const HumanoidSpec* spec = nullptr;

void Check(bool condition, const char* what) {
  if (condition) return;
  std::fprintf(stderr, "invariant broken: %s\n", what);
  std::abort();
}

}  // namespace

void InitializeImportFuzzer() {
  ResourceLimits limits;
  limits.max_clip_frames = 4000;
  limits.max_clip_seconds = 20;
  limits.max_npz_member_bytes = 8 << 20;
  limits.max_decompressed_bytes = 16 << 20;
  SetDefaultResourceLimits(limits);
  auto loaded = HumanoidSpec::LoadDefault();
  if (!loaded.ok()) {
    std::fprintf(stderr, "cannot load the skeleton: %s\n", std::string(loaded.status().message()).c_str());
    std::abort();
  }
  spec = new HumanoidSpec(*std::move(loaded));
}

void FuzzImport(const uint8_t* data, size_t size, const char* extension) {
  // One file per process: libFuzzer's -fork/-jobs workers do not share it.
  static const std::string path = std::string("/tmp/modskill-fuzz-") + std::to_string(::getpid()) + extension;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  auto clip = ImportMotionFile(path, *spec);
  if (!clip.ok()) return;
  const ResourceLimits& limits = DefaultResourceLimits();
  Check(clip->num_frames >= 2 && clip->num_frames <= limits.max_clip_frames, "frame count within limits");
  Check(clip->duration() <= limits.max_clip_seconds + 1.0 / clip->fps, "duration within limits");
  Check(ValidateClipName(clip->name, limits.max_name_length).ok(), "valid clip name");
  Check(clip->body_pos.size() == static_cast<size_t>(clip->num_frames) * clip->num_bodies, "kinematics sized");
  for (const Vec3& p : clip->body_pos) Check(std::isfinite(p.x()) && std::isfinite(p.y()) && std::isfinite(p.z()), "finite bodies");
  for (const Vec3& p : clip->root_pos) Check(p.cwiseAbs().maxCoeff() <= limits.max_position, "root within max_position");
}

}  // namespace modskill::fuzz
