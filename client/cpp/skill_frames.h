// What the skills and compose commands share: a rollout's streamed frames with their skill
// embeddings (RolloutFrame.skill_z), the speed of a body part from them, and a 2-D PCA of many z.
#ifndef MODSKILL_CLIENT_CPP_SKILL_FRAMES_H_
#define MODSKILL_CLIENT_CPP_SKILL_FRAMES_H_

#include <array>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "modskill/v1/modskill.pb.h"

namespace modskill::cli {

// One clip's frames in stream order: simulated body positions [bodies * 3] and z [parts * embed]
// (empty on the last frame).
struct SkillTrack {
  std::string clip;
  std::vector<int> frame;
  std::vector<std::vector<float>> body_pos;
  std::vector<std::vector<float>> z;
  int parts = 0, embed_dim = 0;
};

// Collects frames by clip; the first malformed one is kept as error().
class SkillTrackCollector {
 public:
  void Add(const v1::RolloutFrame& frame);
  const absl::Status& error() const { return error_; }
  // The tracks in the order their clips first came.
  std::vector<SkillTrack>& tracks() { return tracks_; }

 private:
  std::vector<SkillTrack> tracks_;
  absl::Status error_;
};

// Per frame, the mean speed (m/s) of `bodies` (indices into the positions): global, or relative
// to body 0 (the root) when `root_relative`. Frame 0 takes frame 1's speed (forward difference).
std::vector<double> PartSpeed(const SkillTrack& track, const std::vector<int>& bodies, double dt, bool root_relative);

// The two principal axes of `rows` (each of the same size) and each row's coordinates on them.
struct Pca2 {
  std::vector<double> mean;
  std::vector<double> axis[2];
  double explained[2] = {0, 0};  // share of the total variance along each axis
  std::vector<std::array<double, 2>> points;
};
absl::StatusOr<Pca2> PrincipalPlane(const std::vector<std::vector<float>>& rows);

// The part names of the server's layout with `num_parts` parts that has every name of `wanted`,
// and each part's body indices (EnvSpec.body_names order); NOT_FOUND when none has.
struct PartBodies {
  std::string layout;
  std::vector<std::string> names;
  std::vector<std::vector<int>> bodies;
};
absl::StatusOr<PartBodies> FindPartLayout(const std::vector<v1::EnvSpec>& layouts, int num_parts,
                                          const std::vector<std::string>& wanted);

// A float as the shortest decimal that reads back to it (keeps the JSON small).
double Short(float value);
nlohmann::ordered_json FloatRow(const std::vector<float>& values);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_SKILL_FRAMES_H_
