#include "common/policy/family_elites.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "common/shown_value.h"

namespace modskill {

std::string FamilyElitesToJson(const std::vector<FamilyEliteRecord>& elites) {
  nlohmann::json json = nlohmann::json::array();
  for (const FamilyEliteRecord& elite : elites) json.push_back({{"params", elite.params}, {"fitness", elite.fitness}});
  return json.dump();
}

absl::StatusOr<std::vector<FamilyEliteRecord>> FamilyElitesFromJson(absl::string_view text, int dims) {
  const auto bad = [](absl::string_view why) {
    return absl::InvalidArgumentError(absl::StrCat(kCheckpointFamilyElitesFile, ": ", why));
  };
  nlohmann::json json = nlohmann::json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (json.is_discarded() || !json.is_array()) return bad("not a JSON list");
  if (json.size() > static_cast<size_t>(kMaxExportedElites)) return bad(absl::StrCat(json.size(), " elites, more than any run keeps"));
  std::vector<FamilyEliteRecord> elites;
  elites.reserve(json.size());
  try {
    for (size_t k = 0; k < json.size(); ++k) {
      FamilyEliteRecord elite;
      elite.params = json[k].at("params").get<std::vector<double>>();
      elite.fitness = json[k].at("fitness").get<double>();
      bool finite = std::isfinite(elite.fitness);
      for (double value : elite.params) finite &= std::isfinite(value);
      if (static_cast<int>(elite.params.size()) != dims || !finite) {
        return bad(absl::StrCat("[", k, "]: not ", dims, " finite parameters and a finite fitness"));
      }
      elites.push_back(std::move(elite));
    }
  } catch (const nlohmann::json::exception& e) {
    return bad(ShownValue(e.what()));
  }
  return elites;
}

}  // namespace modskill
