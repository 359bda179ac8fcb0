// The elite set a motor-skill family's policy.pt carries (extra file kCheckpointFamilyElitesFile):
// each elite's task parameters a (in the parameters' units, the spec's range order) and its
// fitness F. Torch-free, as policy_spec.h, so that the file can be read, tested and fuzzed alone.
#ifndef MODSKILL_COMMON_POLICY_FAMILY_ELITES_H_
#define MODSKILL_COMMON_POLICY_FAMILY_ELITES_H_

#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill {

inline constexpr char kCheckpointFamilyElitesFile[] = "modskill/family_elites.json";

// More than any run keeps (the k-d tree's elites are episodes that reached the clip's end).
inline constexpr int kMaxExportedElites = 1 << 20;

struct FamilyEliteRecord {
  std::vector<double> params;
  double fitness = 0;
};

std::string FamilyElitesToJson(const std::vector<FamilyEliteRecord>& elites);
// INVALID_ARGUMENT naming the entry for anything but a list of {"params": [dims finite
// numbers], "fitness": a finite number}, at most kMaxExportedElites.
absl::StatusOr<std::vector<FamilyEliteRecord>> FamilyElitesFromJson(absl::string_view json, int dims);

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_FAMILY_ELITES_H_
