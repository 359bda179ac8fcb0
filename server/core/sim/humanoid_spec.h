// The humanoid as numbers: bodies, parents, offsets, collision geometry, hinge ranges and PD
// gains. Immutable once built; scaled copies give other body proportions at run time.
#ifndef MODSKILL_SERVER_CORE_SIM_HUMANOID_SPEC_H_
#define MODSKILL_SERVER_CORE_SIM_HUMANOID_SPEC_H_

#include <array>
#include <map>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/sim/rotation_math.h"

namespace modskill {

struct GeomSpec {
  enum class Type { kSphere, kCapsule, kBox };
  Type type = Type::kSphere;
  double radius = 0;                // sphere and capsule
  Vec3 half_extents = Vec3::Zero();  // box
  Vec3 from = Vec3::Zero();         // capsule segment, body frame
  Vec3 to = Vec3::Zero();
  Vec3 center = Vec3::Zero();       // sphere and box, body frame
  double density = 1000;            // kg/m^3

  double Volume() const;
  // Lowest z of this geometry on a body placed at (pos, rot).
  double LowestPoint(const Vec3& pos, const Quat& rot) const;
  double Mass() const { return Volume() * density; }
};

struct BodySpec {
  std::string name;
  int parent = -1;
  Vec3 offset = Vec3::Zero();  // joint position in the parent's frame (z-up, rest pose)
  GeomSpec geom;
  // Three hinges about the body's x, y, z axes (none for the root); radians.
  std::array<double, 3> range_low{};
  std::array<double, 3> range_high{};
  double kp = 0;            // N*m/rad
  double kd = 0;            // N*m*s/rad
  double torque_limit = 0;  // N*m
};

// Run-time changes of proportions (Lee et al. 2021 parameterize limb lengths and radii).
struct BodyScaling {
  double global_length = 1.0;                    // every offset and geom
  std::map<std::string, double> length_by_body;  // scales that body's geom and its children's offsets
  std::map<std::string, double> radius_by_body;  // scales that body's geom thickness
  double density = 1.0;                          // scales every body's mass
};

class HumanoidSpec {
 public:
  // Reads the skeleton JSON shipped in data/skeleton (PHC's SMPL humanoid as numbers) and
  // converts it to the z-up frame. PD gains follow PHC.
  static absl::StatusOr<HumanoidSpec> LoadFromJson(const std::string& path);
  // The shipped default skeleton, loaded once per process.
  static absl::StatusOr<HumanoidSpec> LoadDefault();

  int num_bodies() const { return static_cast<int>(bodies_.size()); }
  int num_hinges() const { return 3 * (num_bodies() - 1); }
  const BodySpec& body(int i) const { return bodies_[i]; }
  const std::vector<BodySpec>& bodies() const { return bodies_; }
  // -1 when there is no such body.
  int BodyIndex(absl::string_view name) const;
  std::vector<std::string> BodyNames() const;
  // Joint names in hinge order: "<Body>_x", "<Body>_y", "<Body>_z" for every non-root body.
  std::vector<std::string> HingeNames() const;

  // Rest-pose body positions relative to the pelvis.
  std::vector<Vec3> RestPositions() const;
  double TotalMass() const;

  absl::StatusOr<HumanoidSpec> Scaled(const BodyScaling& scaling) const;

 private:
  std::vector<BodySpec> bodies_;
};

// The foot bodies: every body whose name holds "Ankle" or "Toe" (as FootContactRatio).
std::vector<int> FootBodies(const HumanoidSpec& spec);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_HUMANOID_SPEC_H_
