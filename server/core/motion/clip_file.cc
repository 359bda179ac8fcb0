#include "server/core/motion/clip_file.h"

#include <zlib.h>

#include <cstring>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "common/atomic_file.h"
#include "server/core/motion/clip_name.h"

namespace modskill {
namespace {

constexpr char kMagic[8] = {'M', 'S', 'K', 'C', 'L', 'I', 'P', '1'};
constexpr uint32_t kVersion = 1;
constexpr size_t kMaxClipBytes = size_t{1} << 30;
constexpr uint32_t kMaxStringBytes = 1 << 20;

template <typename T>
void Put(std::string* out, T value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

void PutString(std::string* out, const std::string& s) {
  Put<uint32_t>(out, static_cast<uint32_t>(s.size()));
  out->append(s);
}

// Sequential reader that never reads past the end.
class Cursor {
 public:
  explicit Cursor(absl::string_view bytes) : bytes_(bytes) {}
  template <typename T>
  bool Get(T* value) {
    if (bytes_.size() - pos_ < sizeof(T)) return false;
    std::memcpy(value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return true;
  }
  bool GetString(std::string* s) {
    uint32_t length;
    if (!Get(&length) || length > kMaxStringBytes || bytes_.size() - pos_ < length) return false;
    s->assign(bytes_.data() + pos_, length);
    pos_ += length;
    return true;
  }
  size_t remaining() const { return bytes_.size() - pos_; }

 private:
  absl::string_view bytes_;
  size_t pos_ = 0;
};

}  // namespace

std::string EncodeClip(const MotionClip& clip) {
  std::string out(kMagic, sizeof(kMagic));
  Put<uint32_t>(&out, kVersion);
  Put<uint32_t>(&out, static_cast<uint32_t>(clip.num_frames));
  Put<uint32_t>(&out, static_cast<uint32_t>(clip.num_bodies));
  Put<double>(&out, clip.fps);
  for (const std::string* s : {&clip.name, &clip.label, &clip.humanml3d_id, &clip.source}) PutString(&out, *s);
  for (const Vec3& p : clip.root_pos) {
    for (int k = 0; k < 3; ++k) Put<float>(&out, static_cast<float>(p[k]));
  }
  for (const Quat& q : clip.local_rot) {
    for (double v : {q.w(), q.x(), q.y(), q.z()}) Put<float>(&out, static_cast<float>(v));
  }
  const uint32_t crc = crc32(0L, reinterpret_cast<const Bytef*>(out.data()), static_cast<uInt>(out.size()));
  Put<uint32_t>(&out, crc);
  return out;
}

absl::StatusOr<MotionClip> DecodeClip(absl::string_view bytes, absl::string_view what, const ResourceLimits& limits) {
  auto corrupt = [&](absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": not a valid clip file: ", why));
  };
  if (bytes.size() < sizeof(kMagic) + 4 || std::memcmp(bytes.data(), kMagic, sizeof(kMagic)) != 0) {
    return corrupt("bad magic (expected MSKCLIP1)");
  }
  uint32_t stored_crc;
  std::memcpy(&stored_crc, bytes.data() + bytes.size() - 4, 4);
  const uint32_t crc = crc32(0L, reinterpret_cast<const Bytef*>(bytes.data()), static_cast<uInt>(bytes.size() - 4));
  if (crc != stored_crc) return corrupt("checksum mismatch (truncated or damaged)");
  Cursor cursor(bytes.substr(sizeof(kMagic), bytes.size() - sizeof(kMagic) - 4));
  uint32_t version, frames, bodies;
  MotionClip clip;
  if (!cursor.Get(&version) || !cursor.Get(&frames) || !cursor.Get(&bodies) || !cursor.Get(&clip.fps)) {
    return corrupt("header truncated");
  }
  if (version != kVersion) return corrupt(absl::StrCat("version ", version, " (this build reads ", kVersion, ")"));
  if (bodies == 0 || bodies > 256) return corrupt(absl::StrCat("num_bodies ", bodies));
  if (!cursor.GetString(&clip.name) || !cursor.GetString(&clip.label) || !cursor.GetString(&clip.humanml3d_id) ||
      !cursor.GetString(&clip.source)) {
    return corrupt("strings truncated");
  }
  if (auto status = ValidateClipName(clip.name, limits.max_name_length); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": ", status.message()));
  }
  if (auto status = ValidateClipTiming(clip.fps, frames, absl::StrCat(what, ": fps"), limits); !status.ok()) {
    return status;
  }
  const size_t floats_needed = static_cast<size_t>(frames) * (3 + 4 * static_cast<size_t>(bodies));
  if (cursor.remaining() != floats_needed * sizeof(float)) {
    return corrupt(absl::StrCat("payload is ", cursor.remaining(), " bytes, ", frames, " frames x ", bodies,
                                " bodies need ", floats_needed * sizeof(float)));
  }
  clip.num_frames = static_cast<int>(frames);
  clip.num_bodies = static_cast<int>(bodies);
  clip.root_pos.resize(frames);
  clip.local_rot.resize(static_cast<size_t>(frames) * bodies);
  float v[4];
  for (Vec3& p : clip.root_pos) {
    for (int k = 0; k < 3; ++k) cursor.Get(&v[k]);
    p = Vec3(v[0], v[1], v[2]);
  }
  for (Quat& q : clip.local_rot) {
    for (int k = 0; k < 4; ++k) cursor.Get(&v[k]);
    q = Quat(v[0], v[1], v[2], v[3]);
    // float32 storage loses a little norm; renormalize so validation sees unit quaternions.
    if (q.norm() > 0.5) q.normalize();
  }
  if (auto status = ValidateClip(clip, limits); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(what, ": ", status.message()));
  }
  return clip;
}

absl::Status WriteClipFile(const std::string& path, const MotionClip& clip) {
  if (auto status = ValidateClip(clip); !status.ok()) return status;
  return WriteFileAtomically(path, EncodeClip(clip));
}

absl::StatusOr<MotionClip> ReadClipFile(const std::string& path, const HumanoidSpec& spec,
                                        const ResourceLimits& limits) {
  auto bytes = ReadFileToString(path, kMaxClipBytes);
  if (!bytes.ok()) return bytes.status();
  auto clip = DecodeClip(*bytes, path, limits);
  if (!clip.ok()) return clip.status();
  if (auto status = ComputeClipKinematics(spec, &*clip); !status.ok()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", status.message()));
  }
  return clip;
}

}  // namespace modskill
