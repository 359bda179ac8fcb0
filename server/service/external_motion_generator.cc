#include "server/service/external_motion_generator.h"

#include <cmath>

#include <grpcpp/grpcpp.h>

#include "absl/strings/str_cat.h"
#include "common/grpc_status.h"
#include "common/wire/tensor_codec.h"

namespace modskill {
namespace {

// Generated clips longer than this are refused (10 minutes at 30 fps): a guard against a reply
// that would exhaust memory.
constexpr int64_t kMaxGeneratedFrames = 18000;

}  // namespace

void ToMotionData(const HumanoidSpec& spec, const MotionClip& clip, v1::MotionData* data) {
  data->set_name(clip.name);
  data->set_label(clip.label);
  data->set_humanml3d_id(clip.humanml3d_id);
  data->set_fps(clip.fps);
  const int64_t frames = clip.num_frames, bodies = clip.num_bodies;
  std::vector<float> root(static_cast<size_t>(frames * 3)), rot(static_cast<size_t>(frames * bodies * 4));
  for (int64_t f = 0; f < frames; ++f) {
    for (int a = 0; a < 3; ++a) root[f * 3 + a] = static_cast<float>(clip.root_pos[f][a]);
    for (int64_t b = 0; b < bodies; ++b) {
      const Quat& q = clip.local(static_cast<int>(f), static_cast<int>(b));
      float* out = &rot[(f * bodies + b) * 4];
      out[0] = static_cast<float>(q.w());
      out[1] = static_cast<float>(q.x());
      out[2] = static_cast<float>(q.y());
      out[3] = static_cast<float>(q.z());
    }
  }
  SetFloatTensor({frames, 3}, root.data(), data->mutable_root_pos());
  SetFloatTensor({frames, bodies, 4}, rot.data(), data->mutable_local_rot());
  for (const BodySpec& body : spec.bodies()) data->add_body_names(body.name);
}

absl::StatusOr<MotionClip> FromMotionData(const HumanoidSpec& spec, const v1::MotionData& data,
                                          const std::string& field) {
  const int bodies = spec.num_bodies();
  if (data.body_names_size() != bodies) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".body_names: ", data.body_names_size(), " names, the humanoid has ", bodies, " bodies"));
  }
  for (int b = 0; b < bodies; ++b) {
    if (data.body_names(b) != spec.bodies()[b].name) {
      return absl::InvalidArgumentError(absl::StrCat(field, ".body_names[", b, "]: '", data.body_names(b),
                                                     "', expected '", spec.bodies()[b].name, "'"));
    }
  }
  if (!(std::isfinite(data.fps()) && data.fps() > 0 && data.fps() <= 1000)) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".fps: ", data.fps(), " outside (0, 1000]"));
  }
  const auto& shape = data.root_pos().shape();
  if (shape.size() != 2 || shape[0] < 2 || shape[0] > kMaxGeneratedFrames) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".root_pos: shape must be [frames, 3] with 2 <= frames <= ", kMaxGeneratedFrames));
  }
  const int64_t frames = shape[0];
  std::vector<float> root, rot;
  if (absl::Status s = ReadFloatTensor(data.root_pos(), field + ".root_pos", {frames, 3}, &root); !s.ok()) return s;
  if (absl::Status s = ReadFloatTensor(data.local_rot(), field + ".local_rot", {frames, bodies, 4}, &rot); !s.ok()) {
    return s;
  }
  MotionClip clip;
  clip.name = data.name();
  clip.label = data.label();
  clip.humanml3d_id = data.humanml3d_id();
  clip.fps = data.fps();
  clip.num_frames = static_cast<int>(frames);
  clip.num_bodies = bodies;
  for (int64_t f = 0; f < frames; ++f) {
    const Vec3 p(root[f * 3], root[f * 3 + 1], root[f * 3 + 2]);
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z()) || p.cwiseAbs().maxCoeff() > 1e4) {
      return absl::InvalidArgumentError(absl::StrCat(field, ".root_pos: frame ", f, " is not finite or beyond 10 km"));
    }
    clip.root_pos.push_back(p);
    for (int b = 0; b < bodies; ++b) {
      const float* v = &rot[(f * bodies + b) * 4];
      Quat q(v[0], v[1], v[2], v[3]);
      const double norm = q.norm();
      if (!std::isfinite(norm) || std::abs(norm - 1.0) > 0.1) {
        return absl::InvalidArgumentError(
            absl::StrCat(field, ".local_rot: frame ", f, " body ", b, " is not a unit quaternion (norm ", norm, ")"));
      }
      q.normalize();
      clip.local_rot.push_back(q);
    }
  }
  return clip;
}

ExternalMotionGenerator::ExternalMotionGenerator(std::string address, absl::Duration timeout)
    : address_(std::move(address)), timeout_(timeout) {
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(256 << 20);
  args.SetMaxSendMessageSize(256 << 20);
  stub_ = v1::MotionGenerator::NewStub(
      grpc::CreateCustomChannel(address_, grpc::InsecureChannelCredentials(), args));
}

absl::StatusOr<std::vector<MotionVariant>> ExternalMotionGenerator::Generate(const HumanoidSpec& spec,
                                                                            const PartLayout& layout,
                                                                            const MotionClip& parent, int part,
                                                                            uint64_t seed, int count) const {
  const int bodies = spec.num_bodies();
  std::vector<bool> mask(bodies, part < 0);
  if (part >= 0) {
    if (part >= layout.num_parts()) return absl::InvalidArgumentError(absl::StrCat("part: ", part, " out of range"));
    for (int b : layout.parts[part].bodies) mask[b] = true;
  }
  v1::GenerateMotionRequest request;
  request.set_text(parent.label);
  request.set_humanml3d_id(parent.humanml3d_id);
  ToMotionData(spec, parent, request.mutable_parent());
  for (bool m : mask) request.add_part_mask(m);
  if (part >= 0) request.set_part(layout.parts[part].name);
  request.set_count(count);
  request.set_seed(seed);

  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() +
                       std::chrono::microseconds(absl::ToInt64Microseconds(timeout_)));
  v1::GenerateMotionResponse reply;
  const grpc::Status status = stub_->Generate(&context, request, &reply);
  if (!status.ok()) return FromGrpcStatus(status, absl::StrCat("generator ", address_));
  if (reply.clips_size() == 0 || reply.clips_size() > count) {
    return absl::InvalidArgumentError(
        absl::StrCat("generator ", address_, ": clips: ", reply.clips_size(), " clips for a request of ", count));
  }
  const std::string generator = reply.generator().empty() ? absl::StrCat("external:", address_) : reply.generator();
  std::vector<MotionVariant> variants;
  for (int k = 0; k < reply.clips_size(); ++k) {
    const std::string field = absl::StrCat("generator ", address_, ": clips[", k, "]");
    auto clip = FromMotionData(spec, reply.clips(k), field);
    if (!clip.ok()) return clip.status();
    if (part >= 0) {
      if (clip->num_frames != parent.num_frames) {
        return absl::InvalidArgumentError(absl::StrCat(field, ": ", clip->num_frames, " frames, a part-level variant ",
                                                       "keeps the parent's ", parent.num_frames));
      }
      // The other parts keep the reference motion exactly.
      for (int f = 0; f < parent.num_frames; ++f) {
        for (int b = 0; b < bodies; ++b) {
          if (!mask[b]) clip->local(f, b) = parent.local(f, b);
        }
        if (!mask[0]) clip->root_pos[f] = parent.root_pos[f];
      }
      clip->fps = parent.fps;
    }
    if (absl::Status status = ComputeClipKinematics(spec, &*clip); !status.ok()) {
      return absl::InvalidArgumentError(absl::StrCat(field, ": ", status.message()));
    }
    clip->label = parent.label;
    clip->humanml3d_id = parent.humanml3d_id;
    clip->source = absl::StrCat("generated by ", generator, " from '", parent.name, "'");
    MotionVariant variant;
    variant.clip = *std::move(clip);
    variant.provenance = VariantProvenance{parent.name, generator, part, seed};
    variants.push_back(std::move(variant));
  }
  return variants;
}

}  // namespace modskill
