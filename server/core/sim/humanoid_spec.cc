#include "server/core/sim/humanoid_spec.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <fstream>
#include <mutex>
#include <sstream>

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "server/core/util/data_paths.h"

namespace modskill {
namespace {

// The skeleton file is SMPL's native y-up frame; the simulation is z-up facing +x:
// (x, y, z)_yup -> (z, x, y)_zup.
Vec3 YupToZup(const Vec3& v) { return Vec3(v.z(), v.x(), v.y()); }

struct PdGains {
  double kp, kd, torque_limit;
};

// PHC's PD gains by body family (docs/DESIGN.md section 2).
PdGains PhcGainsFor(absl::string_view body) {
  auto has = [&](absl::string_view s) { return absl::StrContains(body, s); };
  if (has("Hip") || has("Knee") || has("Ankle")) return {800, 80, 500};
  if (has("Toe")) return {500, 50, 500};
  if (has("Torso") || has("Spine") || has("Chest")) return {1000, 100, 500};
  if (has("Wrist") || has("Hand")) return {300, 30, 500};
  return {500, 50, 500};  // Neck, Head, Thorax, Shoulder, Elbow
}

absl::StatusOr<Vec3> ReadVec3(const nlohmann::json& j, absl::string_view what) {
  if (!j.is_array() || j.size() != 3) return absl::InvalidArgumentError(absl::StrCat(what, ": expected 3 numbers"));
  for (const auto& x : j) {
    if (!x.is_number()) return absl::InvalidArgumentError(absl::StrCat(what, ": not a number"));
  }
  return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

absl::StatusOr<GeomSpec> ReadGeom(const nlohmann::json& g, absl::string_view body) {
  GeomSpec geom;
  const std::string where = absl::StrCat("body '", body, "' geom");
  if (!g.contains("type") || !g.contains("size") || !g.contains("density")) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": needs type, size and density"));
  }
  const std::string type = g["type"].get<std::string>();
  const auto& size = g["size"];
  geom.density = g["density"].get<double>();
  if (type == "sphere" || type == "box") {
    auto center = ReadVec3(g["pos_yup"], where + ".pos_yup");
    if (!center.ok()) return center.status();
    geom.center = YupToZup(*center);
    if (type == "sphere") {
      geom.type = GeomSpec::Type::kSphere;
      geom.radius = size.at(0).get<double>();
    } else {
      geom.type = GeomSpec::Type::kBox;
      auto half = ReadVec3(size, where + ".size");
      if (!half.ok()) return half.status();
      geom.half_extents = YupToZup(*half);
    }
  } else if (type == "capsule") {
    geom.type = GeomSpec::Type::kCapsule;
    geom.radius = size.at(0).get<double>();
    const auto& ft = g["fromto_yup"];
    if (!ft.is_array() || ft.size() != 6) return absl::InvalidArgumentError(absl::StrCat(where, ".fromto_yup: expected 6 numbers"));
    geom.from = YupToZup(Vec3(ft[0].get<double>(), ft[1].get<double>(), ft[2].get<double>()));
    geom.to = YupToZup(Vec3(ft[3].get<double>(), ft[4].get<double>(), ft[5].get<double>()));
  } else {
    return absl::InvalidArgumentError(absl::StrCat(where, ".type: unknown '", type, "'"));
  }
  return geom;
}

}  // namespace

double GeomSpec::Volume() const {
  switch (type) {
    case Type::kSphere:
      return 4.0 / 3.0 * M_PI * radius * radius * radius;
    case Type::kCapsule:
      return M_PI * radius * radius * ((to - from).norm() + 4.0 / 3.0 * radius);
    case Type::kBox:
      return 8.0 * half_extents.x() * half_extents.y() * half_extents.z();
  }
  return 0;
}

double GeomSpec::LowestPoint(const Vec3& pos, const Quat& rot) const {
  switch (type) {
    case Type::kSphere:
      return (pos + rot * center).z() - radius;
    case Type::kCapsule:
      return std::min((pos + rot * from).z(), (pos + rot * to).z()) - radius;
    case Type::kBox: {
      double lowest = std::numeric_limits<double>::infinity();
      for (int corner = 0; corner < 8; ++corner) {
        const Vec3 c(corner & 1 ? half_extents.x() : -half_extents.x(), corner & 2 ? half_extents.y() : -half_extents.y(),
                     corner & 4 ? half_extents.z() : -half_extents.z());
        lowest = std::min(lowest, (pos + rot * (center + c)).z());
      }
      return lowest;
    }
  }
  return 0;
}

absl::StatusOr<HumanoidSpec> HumanoidSpec::LoadFromJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open skeleton file"));
  std::stringstream text;
  text << in.rdbuf();
  nlohmann::json root = nlohmann::json::parse(text.str(), nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded()) return absl::InvalidArgumentError(absl::StrCat(path, ": not valid JSON"));
  if (!root.contains("bodies") || !root["bodies"].is_array()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": missing array 'bodies'"));
  }
  HumanoidSpec spec;
  try {
    for (const auto& b : root["bodies"]) {
      BodySpec body;
      body.name = b.at("name").get<std::string>();
      body.parent = b.at("parent").get<int>();
      if (body.parent >= static_cast<int>(spec.bodies_.size()) || (body.parent < 0 && !spec.bodies_.empty())) {
        return absl::InvalidArgumentError(absl::StrCat(path, ": body '", body.name, "' has parent ", body.parent,
                                                       " that does not precede it"));
      }
      auto offset = ReadVec3(b.at("offset_yup"), absl::StrCat(path, ": body '", body.name, "'.offset_yup"));
      if (!offset.ok()) return offset.status();
      body.offset = YupToZup(*offset);
      auto geom = ReadGeom(b.at("geom"), body.name);
      if (!geom.ok()) return absl::InvalidArgumentError(absl::StrCat(path, ": ", geom.status().message()));
      body.geom = *geom;
      if (body.parent >= 0) {
        const auto& ranges = b.at("hinge_ranges_deg");
        const char* axes[3] = {"_x", "_y", "_z"};
        for (int a = 0; a < 3; ++a) {
          const std::string key = body.name + axes[a];
          if (!ranges.contains(key)) {
            return absl::InvalidArgumentError(absl::StrCat(path, ": body '", body.name, "' lacks hinge range '", key, "'"));
          }
          body.range_low[a] = ranges[key].at(0).get<double>() * M_PI / 180.0;
          body.range_high[a] = ranges[key].at(1).get<double>() * M_PI / 180.0;
        }
        const PdGains gains = PhcGainsFor(body.name);
        body.kp = gains.kp;
        body.kd = gains.kd;
        body.torque_limit = gains.torque_limit;
      }
      spec.bodies_.push_back(std::move(body));
    }
  } catch (const nlohmann::json::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": malformed body entry: ", e.what()));
  }
  if (spec.bodies_.empty()) return absl::InvalidArgumentError(absl::StrCat(path, ": no bodies"));
  return spec;
}

absl::StatusOr<HumanoidSpec> HumanoidSpec::LoadDefault() {
  static std::once_flag once;
  static absl::StatusOr<HumanoidSpec>* cached = nullptr;
  std::call_once(once, [] {
    cached = new absl::StatusOr<HumanoidSpec>(LoadFromJson(DataPath("skeleton/smpl24_skeleton.json")));
  });
  return *cached;
}

int HumanoidSpec::BodyIndex(absl::string_view name) const {
  for (int i = 0; i < num_bodies(); ++i) {
    if (bodies_[i].name == name) return i;
  }
  return -1;
}

std::vector<std::string> HumanoidSpec::BodyNames() const {
  std::vector<std::string> names;
  for (const auto& b : bodies_) names.push_back(b.name);
  return names;
}

std::vector<std::string> HumanoidSpec::HingeNames() const {
  std::vector<std::string> names;
  for (int i = 1; i < num_bodies(); ++i) {
    for (const char* axis : {"_x", "_y", "_z"}) names.push_back(bodies_[i].name + axis);
  }
  return names;
}

std::vector<Vec3> HumanoidSpec::RestPositions() const {
  std::vector<Vec3> pos(bodies_.size(), Vec3::Zero());
  for (size_t i = 1; i < bodies_.size(); ++i) pos[i] = pos[bodies_[i].parent] + bodies_[i].offset;
  return pos;
}

double HumanoidSpec::TotalMass() const {
  double mass = 0;
  for (const auto& b : bodies_) mass += b.geom.Mass();
  return mass;
}

absl::StatusOr<HumanoidSpec> HumanoidSpec::Scaled(const BodyScaling& scaling) const {
  auto check_factor = [](absl::string_view what, double f) -> absl::Status {
    if (!(f > 0.05 && f < 20.0)) {
      return absl::InvalidArgumentError(absl::StrCat(what, ": scale factor ", f, " outside (0.05, 20)"));
    }
    return absl::OkStatus();
  };
  if (auto s = check_factor("global_length", scaling.global_length); !s.ok()) return s;
  if (auto s = check_factor("density", scaling.density); !s.ok()) return s;
  for (const auto* table : {&scaling.length_by_body, &scaling.radius_by_body}) {
    for (const auto& [name, factor] : *table) {
      if (BodyIndex(name) < 0) return absl::InvalidArgumentError(absl::StrCat("body scaling: unknown body '", name, "'"));
      if (auto s = check_factor(name, factor); !s.ok()) return s;
    }
  }
  HumanoidSpec out = *this;
  for (size_t i = 0; i < out.bodies_.size(); ++i) {
    BodySpec& body = out.bodies_[i];
    auto length_it = scaling.length_by_body.find(body.name);
    const double own_length = scaling.global_length * (length_it == scaling.length_by_body.end() ? 1.0 : length_it->second);
    double parent_length = scaling.global_length;
    if (body.parent >= 0) {
      auto parent_it = scaling.length_by_body.find(bodies_[body.parent].name);
      if (parent_it != scaling.length_by_body.end()) parent_length *= parent_it->second;
    }
    body.offset *= parent_length;  // a longer parent pushes this joint further out
    auto radius_it = scaling.radius_by_body.find(body.name);
    const double radius = scaling.global_length * (radius_it == scaling.radius_by_body.end() ? 1.0 : radius_it->second);
    GeomSpec& g = body.geom;
    g.from *= own_length;
    g.to *= own_length;
    g.center *= own_length;
    g.radius *= radius;
    g.half_extents *= radius;
    g.density *= scaling.density;
  }
  return out;
}

std::vector<int> FootBodies(const HumanoidSpec& spec) {
  std::vector<int> feet;
  for (int b = 0; b < spec.num_bodies(); ++b) {
    if (absl::StrContains(spec.body(b).name, "Ankle") || absl::StrContains(spec.body(b).name, "Toe")) feet.push_back(b);
  }
  return feet;
}

}  // namespace modskill
