// The client side of the MotionGenerator service (proto/modskill/v1/modskill.proto): asks an
// external generator (a text-to-motion model served from Python, for instance) for variants of
// a failed clip, with a deadline, and checks everything it sends back before the server uses it.
#ifndef MODSKILL_SERVER_SERVICE_EXTERNAL_MOTION_GENERATOR_H_
#define MODSKILL_SERVER_SERVICE_EXTERNAL_MOTION_GENERATOR_H_

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "modskill/v1/modskill.grpc.pb.h"
#include "server/core/curriculum/motion_variants.h"
#include "server/core/sim/humanoid_spec.h"
#include "server/core/sim/part_layout.h"

namespace modskill {

// MotionClip <-> MotionData (root positions and local rotations only, as FLOAT32).
void ToMotionData(const HumanoidSpec& spec, const MotionClip& clip, v1::MotionData* data);
// Checks body names, shapes, finiteness and unit quaternions (renormalized within 10 %); the
// kinematics are left to the caller (ComputeClipKinematics). Errors name `field` and the
// offending part.
absl::StatusOr<MotionClip> FromMotionData(const HumanoidSpec& spec, const v1::MotionData& data,
                                          const std::string& field);

class ExternalMotionGenerator {
 public:
  // Connects lazily: a generator that is down only fails the calls made while it is.
  ExternalMotionGenerator(std::string address, absl::Duration timeout);

  const std::string& address() const { return address_; }

  // `count` variants of `parent` (part -1: whole body; else one part of `layout`), with their
  // provenance. For part-level requests the parent's rotations are put back on every body
  // outside the part (and the parent's root unless the part holds the pelvis), so a generator
  // cannot disturb the other parts. Errors: UNAVAILABLE (down), DEADLINE_EXCEEDED (slow), or
  // INVALID_ARGUMENT naming the reply's field (malformed): the caller logs and falls back.
  absl::StatusOr<std::vector<MotionVariant>> Generate(const HumanoidSpec& spec, const PartLayout& layout,
                                                      const MotionClip& parent, int part, uint64_t seed,
                                                      int count) const;

 private:
  const std::string address_;
  const absl::Duration timeout_;
  std::unique_ptr<v1::MotionGenerator::Stub> stub_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_SERVICE_EXTERNAL_MOTION_GENERATOR_H_
