#include "server/core/sim/part_layout.h"

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/atomic_file.h"
#include "common/name_lookup.h"
#include "common/shown_value.h"
#include "server/core/util/data_paths.h"

namespace modskill {

std::vector<std::string> PartLayout::PartNames() const {
  std::vector<std::string> names;
  for (const BodyPart& part : parts) names.push_back(part.name);
  return names;
}

std::vector<int> PartLayout::BodyOrder() const {
  std::vector<int> order;
  for (const BodyPart& part : parts) order.insert(order.end(), part.bodies.begin(), part.bodies.end());
  return order;
}

absl::StatusOr<std::vector<int>> PartLayout::BodiesOfParts(const std::vector<std::string>& names,
                                                          absl::string_view field) const {
  auto indices = IndicesOfNames(names, PartNames(), field, absl::StrCat("a part of layout '", name, "'"));
  if (!indices.ok()) return indices.status();
  std::vector<int> bodies;
  for (int p : *indices) bodies.insert(bodies.end(), parts[p].bodies.begin(), parts[p].bodies.end());
  return bodies;
}

absl::StatusOr<PartLayout> MakePartLayout(const std::string& name,
                                          const std::vector<std::pair<std::string, std::vector<std::string>>>& parts,
                                          const HumanoidSpec& spec) {
  PartLayout layout;
  layout.name = name;
  std::vector<int> owner(spec.num_bodies(), -1);
  for (const auto& [part_name, body_names] : parts) {
    BodyPart part;
    part.name = part_name;
    if (body_names.empty()) return absl::InvalidArgumentError(absl::StrCat("layout '", name, "' part '", part_name, "' is empty"));
    for (const std::string& body_name : body_names) {
      const int body = spec.BodyIndex(body_name);
      if (body < 0) {
        return absl::InvalidArgumentError(absl::StrCat("layout '", name, "' part '", part_name, "': unknown body '", body_name, "'"));
      }
      if (owner[body] >= 0) {
        return absl::InvalidArgumentError(absl::StrCat("layout '", name, "': body '", body_name, "' is in two parts"));
      }
      owner[body] = layout.num_parts();
      part.bodies.push_back(body);
    }
    layout.parts.push_back(std::move(part));
  }
  std::vector<std::string> missing;
  for (int b = 0; b < spec.num_bodies(); ++b) {
    if (owner[b] < 0) missing.push_back(spec.body(b).name);
  }
  if (!missing.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("layout '", name, "' leaves out bodies: ", absl::StrJoin(missing, ", ")));
  }
  return layout;
}

absl::StatusOr<PartLayoutCatalog> PartLayoutCatalog::LoadFromJson(const std::string& path, const HumanoidSpec& spec) {
  auto text = ReadFileToString(path, 1 << 20);
  if (!text.ok()) return text.status();
  nlohmann::json root = nlohmann::json::parse(*text, nullptr, /*allow_exceptions=*/false);
  if (root.is_discarded() || !root.contains("layouts") || !root["layouts"].is_object()) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": expected a JSON object with 'layouts'"));
  }
  PartLayoutCatalog catalog;
  try {
    for (const auto& [name, parts_json] : root["layouts"].items()) {
      std::vector<std::pair<std::string, std::vector<std::string>>> parts;
      for (const auto& part : parts_json) {
        parts.emplace_back(part.at("name").get<std::string>(), part.at("bodies").get<std::vector<std::string>>());
      }
      auto layout = MakePartLayout(name, parts, spec);
      if (!layout.ok()) return absl::InvalidArgumentError(absl::StrCat(path, ": ", layout.status().message()));
      catalog.layouts_[name] = *std::move(layout);
    }
    catalog.default_name_ = root.value("default", std::string());
  } catch (const nlohmann::json::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": malformed layout: ", e.what()));
  }
  if (catalog.layouts_.count(catalog.default_name_) == 0) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": default layout '", catalog.default_name_, "' is not defined"));
  }
  return catalog;
}

absl::StatusOr<PartLayoutCatalog> PartLayoutCatalog::LoadDefault(const HumanoidSpec& spec) {
  return LoadFromJson(DataPath("part_layouts.json"), spec);
}

absl::StatusOr<PartLayout> PartLayoutCatalog::Get(absl::string_view name) const {
  auto it = layouts_.find(std::string(name));
  if (it == layouts_.end()) {
    return absl::NotFoundError(absl::StrCat("part_layout: unknown layout '", ShownValue(name), "' (known: ",
                                            absl::StrJoin(Names(), ", "), ")"));
  }
  return it->second;
}

std::vector<std::string> PartLayoutCatalog::Names() const {
  std::vector<std::string> names;
  for (const auto& [name, layout] : layouts_) names.push_back(name);
  return names;
}

}  // namespace modskill
