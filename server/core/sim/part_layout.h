// How the body is split into parts, each with its own observation and action slice. Layouts
// are data (data/part_layouts.json), so new splits need no code.
#ifndef MODSKILL_SERVER_CORE_SIM_PART_LAYOUT_H_
#define MODSKILL_SERVER_CORE_SIM_PART_LAYOUT_H_

#include <map>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct BodyPart {
  std::string name;
  std::vector<int> bodies;  // spec body indices, in layout order
};

struct PartLayout {
  std::string name;
  std::vector<BodyPart> parts;
  int num_parts() const { return static_cast<int>(parts.size()); }
  // Every body once, part after part: the order of bodies in observations and actions.
  std::vector<int> BodyOrder() const;
  std::vector<std::string> PartNames() const;
  // The bodies of the named parts, part after part; INVALID_ARGUMENT naming `field`[i] for a name
  // that is not a part of this layout or is given twice.
  absl::StatusOr<std::vector<int>> BodiesOfParts(const std::vector<std::string>& names, absl::string_view field) const;
};

// Checks that every body of `spec` appears in exactly one part.
absl::StatusOr<PartLayout> MakePartLayout(const std::string& name,
                                          const std::vector<std::pair<std::string, std::vector<std::string>>>& parts,
                                          const HumanoidSpec& spec);

class PartLayoutCatalog {
 public:
  static absl::StatusOr<PartLayoutCatalog> LoadFromJson(const std::string& path, const HumanoidSpec& spec);
  static absl::StatusOr<PartLayoutCatalog> LoadDefault(const HumanoidSpec& spec);

  absl::StatusOr<PartLayout> Get(absl::string_view name) const;
  const std::string& default_name() const { return default_name_; }
  std::vector<std::string> Names() const;

 private:
  std::map<std::string, PartLayout> layouts_;
  std::string default_name_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_PART_LAYOUT_H_
