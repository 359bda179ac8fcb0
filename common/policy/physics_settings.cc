#include "common/policy/physics_settings.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/servo_settings.h"
#include "common/shown_value.h"

namespace modskill {
namespace {

std::string Rate(double physics_dt) { return absl::StrFormat("%g s (%.0f Hz)", physics_dt, 1.0 / physics_dt); }

}  // namespace

std::string PhysicsSettings::ToJson() const {
  nlohmann::json json;
  json["physics_dt"] = physics_dt;
  json["pd_mode"] = pd_mode;
  json["pd_gain_scale"] = pd_gain_scale;
  json["damp_to_reference_rate"] = damp_to_reference_rate;
  return json.dump();
}

absl::StatusOr<PhysicsSettings> PhysicsSettings::FromJson(absl::string_view text, absl::string_view where) {
  const auto bad = [&](absl::string_view field, absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": physics.", field, ": ", why));
  };
  nlohmann::json json = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded() || !json.is_object()) {
    return absl::InvalidArgumentError(absl::StrCat(where, ": physics: not a JSON object"));
  }
  PhysicsSettings settings;
  const char* const numbers[] = {"physics_dt", "pd_gain_scale"};
  for (const char* key : numbers) {
    if (!json.contains(key) || !json.at(key).is_number()) return bad(key, "missing or not a number");
  }
  settings.physics_dt = json.at("physics_dt").get<double>();
  if (!(settings.physics_dt > 0 && settings.physics_dt <= 1)) {
    return bad("physics_dt", absl::StrCat(settings.physics_dt, " is not in (0, 1] s"));
  }
  settings.pd_gain_scale = json.at("pd_gain_scale").get<double>();
  if (absl::Status status = ValidatePdGainScale(settings.pd_gain_scale, absl::StrCat(where, ": physics.pd_gain_scale"));
      !status.ok()) {
    return status;
  }
  if (!json.contains("pd_mode") || !json.at("pd_mode").is_string() ||
      !IsPdModeName(json.at("pd_mode").get_ref<const std::string&>())) {
    return bad("pd_mode", absl::StrCat(json.contains("pd_mode") ? ShownValue(json.at("pd_mode").dump()) : "missing",
                                       " is not ", kPdModeChoices));
  }
  settings.pd_mode = json.at("pd_mode").get<std::string>();
  if (!json.contains("damp_to_reference_rate") || !json.at("damp_to_reference_rate").is_boolean()) {
    return bad("damp_to_reference_rate", "missing or not true/false");
  }
  settings.damp_to_reference_rate = json.at("damp_to_reference_rate").get<bool>();
  return settings;
}

std::string PhysicsDifference(const PhysicsSettings& mine, const PhysicsSettings& theirs, absl::string_view theirs_name) {
  if (!mine.recorded() || !theirs.recorded()) return "";
  if (std::abs(mine.physics_dt - theirs.physics_dt) > 1e-6 * mine.physics_dt) {
    return absl::StrCat("physics_dt ", Rate(mine.physics_dt), " against ", theirs_name, " ", Rate(theirs.physics_dt),
                        "; the server's --substeps sets it");
  }
  if (mine.pd_mode != theirs.pd_mode) {
    return absl::StrCat("pd_mode ", mine.pd_mode, " against ", theirs_name, " ", theirs.pd_mode,
                        "; the server's --pd_mode sets it");
  }
  if (std::abs(mine.pd_gain_scale - theirs.pd_gain_scale) > 1e-9 * mine.pd_gain_scale) {
    return absl::StrCat("pd_gain_scale ", mine.pd_gain_scale, " against ", theirs_name, " ", theirs.pd_gain_scale,
                        "; the server's --pd_gain_scale sets it");
  }
  if (mine.damp_to_reference_rate != theirs.damp_to_reference_rate) {
    const auto on_off = [](bool on) { return on ? "on" : "off"; };
    return absl::StrCat("damp_to_reference_rate ", on_off(mine.damp_to_reference_rate), " against ", theirs_name, " ",
                        on_off(theirs.damp_to_reference_rate), "; the server's --damp_to_reference_rate sets it");
  }
  return "";
}

}  // namespace modskill
