#include "learner/episode_ends.h"

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "common/wire/tensor_codec.h"

namespace modskill::learner {
namespace {

// END_CAUSE_BLOW_UP -> "blow_up".
std::string ShortName(int cause) {
  std::string name = v1::EndCause_Name(static_cast<v1::EndCause>(cause));
  name = name.substr(std::string("END_CAUSE_").size());
  absl::AsciiStrToLower(&name);
  return name;
}

}  // namespace

void EpisodeEnds::Add(int cause) { ++count_[cause >= 0 && cause < kCauses ? cause : v1::END_CAUSE_UNSPECIFIED]; }

void EpisodeEnds::Merge(const EpisodeEnds& other) {
  for (int c = 0; c < kCauses; ++c) count_[c] += other.count_[c];
}

int EpisodeEnds::total() const {
  int sum = 0;
  for (int c : count_) sum += c;
  return sum;
}

std::string EpisodeEnds::Summary() const {
  std::vector<std::string> parts;
  for (int c = v1::END_CAUSE_TIME; c < kCauses; ++c) {
    if (count_[c] > 0) parts.push_back(absl::StrCat(ShortName(c), " ", count_[c]));
  }
  if (count_[v1::END_CAUSE_UNSPECIFIED] > 0) parts.push_back(absl::StrCat("unreported ", count_[0]));
  return parts.empty() ? "-" : absl::StrJoin(parts, ", ");
}

std::vector<std::string> EpisodeEnds::Names() {
  std::vector<std::string> names;
  for (int c = v1::END_CAUSE_TIME; c < kCauses; ++c) names.push_back(ShortName(c));
  return names;
}

std::vector<int> EpisodeEnds::Counts() const {
  return std::vector<int>(count_.begin() + v1::END_CAUSE_TIME, count_.end());
}

absl::StatusOr<std::vector<int>> ReadEndCauses(const v1::StepResult& result, int n) {
  if (!result.has_end_cause() || result.end_cause().shape_size() == 0) return std::vector<int>{};
  if (absl::Status status = AsDataLoss(CheckTensor(result.end_cause(), "StepResult.end_cause", v1::UINT8, {n}));
      !status.ok()) {
    return status;
  }
  const auto* bytes = reinterpret_cast<const uint8_t*>(result.end_cause().data().data());
  return std::vector<int>(bytes, bytes + n);
}

}  // namespace modskill::learner
