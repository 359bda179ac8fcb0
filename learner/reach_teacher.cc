#include "learner/reach_teacher.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "common/atomic_file.h"
#include "common/shown_value.h"

namespace modskill::learner {
namespace {

constexpr int64_t kMaxEmbedDim = 4096;

std::vector<std::string> Words(absl::string_view line) {
  return absl::StrSplit(line, absl::ByAnyChar(" \t\r"), absl::SkipEmpty());
}

}  // namespace

absl::StatusOr<ReachTeacher> ReachTeacher::Parse(const std::string& text, const std::string& origin) {
  ReachTeacher teacher;
  int64_t embed_dim = 0;
  std::vector<float> points, z;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    ++line_number;
    const auto bad = [&](absl::string_view why) {
      return absl::InvalidArgumentError(absl::StrCat(origin, ":", line_number, ": ", why));
    };
    const std::vector<std::string> words = Words(line);
    if (words.empty() || words[0][0] == '#') continue;
    if (words[0] == "parts") {
      if (!teacher.parts_.empty()) return bad("a second 'parts' line");
      teacher.parts_.assign(words.begin() + 1, words.end());
      if (teacher.parts_.empty()) return bad("'parts' names no part");
    } else if (words[0] == "embed_dim") {
      if (words.size() != 2 || !absl::SimpleAtoi(words[1], &embed_dim) || embed_dim < 1 || embed_dim > kMaxEmbedDim) {
        return bad(absl::StrCat("embed_dim must be one integer in [1, ", kMaxEmbedDim, "]"));
      }
    } else if (words[0] == "entry") {
      if (teacher.parts_.empty() || embed_dim == 0) return bad("an entry before the 'parts' and 'embed_dim' lines");
      const size_t values = 3 + teacher.parts_.size() * embed_dim;
      if (words.size() != 2 + values) {
        return bad(absl::StrCat("entry '", ShownValue(words.size() > 1 ? words[1] : ""), "' has ",
                                words.size() < 2 ? 0 : words.size() - 2, " numbers, expected ", values,
                                " (x y z and ", teacher.parts_.size(), " × ", embed_dim, " z)"));
      }
      std::vector<float> row(values);
      for (size_t i = 0; i < values; ++i) {
        if (!absl::SimpleAtof(words[2 + i], &row[i]) || !std::isfinite(row[i])) {
          return bad(absl::StrCat("entry '", ShownValue(words[1]), "' number ", i + 1, ": '", ShownValue(words[2 + i]),
                                  "' is not a finite number"));
        }
      }
      points.insert(points.end(), row.begin(), row.begin() + 3);
      z.insert(z.end(), row.begin() + 3, row.end());
    } else {
      return bad(absl::StrCat("unknown line '", ShownValue(words[0]), "' (parts, embed_dim, entry or # comment)"));
    }
  }
  if (points.empty()) return absl::InvalidArgumentError(absl::StrCat(origin, ": no entries"));
  const int64_t k = static_cast<int64_t>(points.size() / 3);
  const int64_t num_parts = static_cast<int64_t>(teacher.parts_.size());
  teacher.points_ = torch::tensor(points).view({k, 3});
  const torch::Tensor raw = torch::tensor(z).view({k, num_parts, embed_dim});
  const torch::Tensor norms = raw.norm(2, -1, /*keepdim=*/true);
  if ((norms < 1e-6).any().item<bool>()) {
    return absl::InvalidArgumentError(absl::StrCat(origin, ": an entry has a zero z (not on the sphere)"));
  }
  teacher.z_ = raw / norms;
  return teacher;
}

absl::StatusOr<ReachTeacher> ReachTeacher::Load(const std::string& path) {
  absl::StatusOr<std::string> text = ReadFileToString(path, kMaxFileBytes);
  if (!text.ok()) return absl::Status(text.status().code(), absl::StrCat("--task_teacher: ", text.status().message()));
  return Parse(*text, absl::StrCat("--task_teacher ", path));
}

absl::StatusOr<torch::Tensor> ReachTeacher::PartMask(const NetworkLayout& layout, int64_t embed_dim,
                                                     const std::vector<std::string>& task_parts) const {
  std::vector<std::string> layout_parts;
  for (const PartSlices& part : layout.parts) layout_parts.push_back(part.name);
  if (parts_ != layout_parts || z_.size(2) != embed_dim) {
    return absl::FailedPreconditionError(absl::StrCat(
        "--task_teacher: its z are for parts (", absl::StrJoin(parts_, ","), ") of ", z_.size(2),
        " dims, the skills' for (", absl::StrJoin(layout_parts, ","), ") of ", embed_dim,
        " (make it from these skills with bench/reach_teacher.py)"));
  }
  if (layout.goal_size != 3) {
    return absl::FailedPreconditionError(absl::StrCat("--task_teacher: the task's goal has ", layout.goal_size,
                                                      " features, the teacher reads 3 (a target point)"));
  }
  torch::Tensor mask = torch::zeros({static_cast<int64_t>(parts_.size())});
  for (size_t p = 0; p < parts_.size(); ++p) {
    const bool supervised =
        task_parts.empty() || std::find(task_parts.begin(), task_parts.end(), parts_[p]) != task_parts.end();
    if (supervised) mask[static_cast<int64_t>(p)] = 1.f;
  }
  return mask;
}

torch::Tensor ReachTeacher::NearestZ(const torch::Tensor& goals) const {
  const torch::Tensor nearest = torch::cdist(goals.to(torch::kFloat), points_).argmin(1);  // [N]
  return z_.index_select(0, nearest);
}

torch::Tensor TeacherLoss(const torch::Tensor& z, const torch::Tensor& teacher, const torch::Tensor& part_mask) {
  const torch::Tensor per_part = (z - teacher).square().sum(-1);  // [N, P]
  return (per_part * part_mask).sum(-1).mean() / part_mask.sum().clamp_min(1);
}

double TeacherWeightAt(double weight, int64_t fade_steps, int64_t env_steps) {
  if (fade_steps <= 0) return weight;
  return weight * std::max(0.0, 1.0 - static_cast<double>(env_steps) / static_cast<double>(fade_steps));
}

}  // namespace modskill::learner
