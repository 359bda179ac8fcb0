#include "server/core/sim/mjcf_builder.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace modskill {
namespace {

std::string V3(const Vec3& v) { return absl::StrFormat("%.6f %.6f %.6f", v.x(), v.y(), v.z()); }

std::string GeomXml(const BodySpec& body, const PhysicsOptions& options) {
  const GeomSpec& g = body.geom;
  // Without self collision the bodies touch only the floor: contype 1 meets the floor's
  // conaffinity 1, conaffinity 0 ignores other bodies.
  const std::string collide = options.self_collision ? "contype=\"1\" conaffinity=\"1\"" : "contype=\"1\" conaffinity=\"0\"";
  std::string shape;
  switch (g.type) {
    case GeomSpec::Type::kSphere:
      shape = absl::StrFormat("type=\"sphere\" size=\"%.6f\" pos=\"%s\"", g.radius, V3(g.center));
      break;
    case GeomSpec::Type::kCapsule:
      shape = absl::StrFormat("type=\"capsule\" size=\"%.6f\" fromto=\"%s %s\"", g.radius, V3(g.from), V3(g.to));
      break;
    case GeomSpec::Type::kBox:
      shape = absl::StrFormat("type=\"box\" size=\"%s\" pos=\"%s\"", V3(g.half_extents), V3(g.center));
      break;
  }
  return absl::StrFormat("<geom name=\"%s\" %s %s density=\"%.6f\"/>\n", body.name, shape, collide, g.density);
}

void AppendBody(const HumanoidSpec& spec, const PhysicsOptions& options, int index, int depth, std::string* xml) {
  const BodySpec& body = spec.body(index);
  const std::string indent(2 * depth, ' ');
  Vec3 pos = body.offset;
  if (index == 0) pos = Vec3(0, 0, options.fixed_root ? options.fixed_root_height : 0.95);
  absl::StrAppend(xml, indent, absl::StrFormat("<body name=\"%s\" pos=\"%s\">\n", body.name, V3(pos)));
  if (index == 0) {
    if (!options.fixed_root) absl::StrAppend(xml, indent, "  <freejoint name=\"", body.name, "\"/>\n");
  } else {
    // PHC's hinge names and ranges belong to its y-up frame: _x, _y, _z turn about z-up +y, +z, +x
    // (HingeAxis in rotation_math.h).
    const char* axes[3] = {"0 1 0", "0 0 1", "1 0 0"};
    const char* suffix[3] = {"_x", "_y", "_z"};
    // Stable PD computes its own damping; the implicit mode lets MuJoCo integrate kd.
    const double damping =
        options.pd_mode == PdMode::kPositionImplicitDamping ? options.pd_gain_scale * body.kd : 0.0;
    for (int a = 0; a < 3; ++a) {
      absl::StrAppend(xml, indent,
                      absl::StrFormat("  <joint name=\"%s%s\" type=\"hinge\" axis=\"%s\" range=\"%.6f %.6f\" "
                                      "damping=\"%.3f\" armature=\"%.4f\" limited=\"true\"/>\n",
                                      body.name, suffix[a], axes[a], body.range_low[a], body.range_high[a], damping,
                                      options.armature));
    }
  }
  absl::StrAppend(xml, indent, "  ", GeomXml(body, options));
  for (int child = index + 1; child < spec.num_bodies(); ++child) {
    if (spec.body(child).parent == index) AppendBody(spec, options, child, depth + 1, xml);
  }
  absl::StrAppend(xml, indent, "</body>\n");
}

}  // namespace

std::string BuildHumanoidMjcf(const HumanoidSpec& spec, const PhysicsOptions& options) {
  std::string xml = "<mujoco model=\"modskill_smpl24\">\n";
  absl::StrAppend(&xml, "  <compiler angle=\"radian\" inertiafromgeom=\"true\"/>\n");
  absl::StrAppend(&xml, absl::StrFormat("  <option timestep=\"%.8f\" integrator=\"Euler\" gravity=\"0 0 -9.81\"/>\n",
                                        options.physics_dt()));
  // MuJoCo's default stack is ~18 MB per mjData, and resets and creation touch all of it.
  // Tracking rollouts peak near 20 contacts and 80 constraint rows using ~30k stack doubles;
  // these bounds leave a 3x margin, and overflowing contacts only raise a warning.
  absl::StrAppend(&xml, "  <size njmax=\"250\" nconmax=\"64\" nstack=\"150000\"/>\n");
  absl::StrAppend(&xml, absl::StrFormat("  <default><geom condim=\"3\" friction=\"%.4f 0.005 0.0001\"/></default>\n",
                                        options.friction));
  absl::StrAppend(&xml, "  <worldbody>\n");
  absl::StrAppend(&xml, "    <geom name=\"floor\" type=\"plane\" size=\"100 100 0.2\" contype=\"1\" conaffinity=\"1\"/>\n");
  if (options.family_obstacle) {
    absl::StrAppend(&xml, "    <geom name=\"", kFamilyObstacleName,
                    "\" type=\"box\" pos=\"0 0 -5\" size=\"0.05 1 0.05\" contype=\"1\" conaffinity=\"1\"/>\n");
  }
  AppendBody(spec, options, 0, 2, &xml);
  if (options.strike_target) {
    // A 0.4 x 0.4 x 1.8 m pillar of 14.4 kg, colliding with the floor and every body.
    absl::StrAppend(&xml, absl::StrFormat("    <body name=\"%s\" pos=\"3 0 %.3f\">\n", kStrikeTargetName,
                                          kStrikeTargetHalfExtents[2]));
    absl::StrAppend(&xml, "      <freejoint name=\"", kStrikeTargetName, "\"/>\n");
    absl::StrAppend(&xml, absl::StrFormat("      <geom name=\"%s\" type=\"box\" size=\"%.3f %.3f %.3f\" contype=\"1\" "
                                          "conaffinity=\"1\" density=\"50\"/>\n",
                                          kStrikeTargetName, kStrikeTargetHalfExtents[0], kStrikeTargetHalfExtents[1],
                                          kStrikeTargetHalfExtents[2]));
    absl::StrAppend(&xml, "    </body>\n");
  }
  absl::StrAppend(&xml, "  </worldbody>\n");
  if (options.pd_mode == PdMode::kPositionImplicitDamping) {
    // Position servo: force = kp * (ctrl - q), clamped to the torque limit.
    absl::StrAppend(&xml, "  <actuator>\n");
    for (int i = 1; i < spec.num_bodies(); ++i) {
      const BodySpec& body = spec.body(i);
      for (const char* suffix : {"_x", "_y", "_z"}) {
        absl::StrAppend(&xml, absl::StrFormat("    <general name=\"%s%s\" joint=\"%s%s\" gaintype=\"fixed\" "
                                              "gainprm=\"%.3f\" biastype=\"affine\" biasprm=\"0 %.3f 0\" "
                                              "forcelimited=\"true\" forcerange=\"%.3f %.3f\"/>\n",
                                              body.name, suffix, body.name, suffix, options.pd_gain_scale * body.kp,
                                              -options.pd_gain_scale * body.kp,
                                              -body.torque_limit, body.torque_limit));
      }
    }
    absl::StrAppend(&xml, "  </actuator>\n");
  }
  absl::StrAppend(&xml, "</mujoco>\n");
  return xml;
}

}  // namespace modskill
