#include "client/cpp/skill_frames.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdlib>

#include "absl/strings/str_cat.h"
#include "common/wire/tensor_codec.h"

namespace modskill::cli {

void SkillTrackCollector::Add(const v1::RolloutFrame& frame) {
  if (!error_.ok()) return;
  std::vector<float> pos, z;
  error_ = ReadFloatTensor(frame.sim_body_pos(), "RolloutFrame.sim_body_pos", &pos);
  if (error_.ok() && frame.has_skill_z() && frame.skill_z().shape_size() > 0) {
    error_ = ReadFloatTensor(frame.skill_z(), "RolloutFrame.skill_z", &z);
    if (error_.ok() && frame.skill_z().shape_size() != 2) {
      error_ = absl::DataLossError("RolloutFrame.skill_z: expected [parts, embed_dim]");
    }
  }
  if (!error_.ok()) return;
  auto it = std::find_if(tracks_.begin(), tracks_.end(), [&](const SkillTrack& t) { return t.clip == frame.clip(); });
  if (it == tracks_.end()) {
    tracks_.push_back(SkillTrack{frame.clip()});
    it = tracks_.end() - 1;
  }
  if (!z.empty()) {
    it->parts = static_cast<int>(frame.skill_z().shape(0));
    it->embed_dim = static_cast<int>(frame.skill_z().shape(1));
  }
  it->frame.push_back(frame.frame());
  it->body_pos.push_back(std::move(pos));
  it->z.push_back(std::move(z));
}

std::vector<double> PartSpeed(const SkillTrack& track, const std::vector<int>& bodies, double dt, bool root_relative) {
  const size_t frames = track.body_pos.size();
  std::vector<double> speed(frames, 0.0);
  auto at = [&](size_t f, int body, int axis) {
    const std::vector<float>& p = track.body_pos[f];
    return double{p[body * 3 + axis]} - (root_relative ? double{p[axis]} : 0.0);
  };
  for (size_t f = 1; f < frames; ++f) {
    double sum = 0;
    for (int body : bodies) {
      double squared = 0;
      for (int axis = 0; axis < 3; ++axis) {
        const double d = at(f, body, axis) - at(f - 1, body, axis);
        squared += d * d;
      }
      sum += std::sqrt(squared) / dt;
    }
    speed[f] = bodies.empty() ? 0.0 : sum / bodies.size();
  }
  if (frames >= 2) speed[0] = speed[1];
  return speed;
}

namespace {

// The leading eigenvector of the symmetric matrix c [n, n] by power iteration.
std::vector<double> LeadingAxis(const std::vector<double>& c, size_t n) {
  std::vector<double> v(n), next(n);
  for (size_t i = 0; i < n; ++i) v[i] = 1.0 + 0.01 * i;  // not orthogonal to any axis in practice
  for (int iteration = 0; iteration < 500; ++iteration) {
    double norm = 0;
    for (size_t i = 0; i < n; ++i) {
      next[i] = 0;
      for (size_t j = 0; j < n; ++j) next[i] += c[i * n + j] * v[j];
      norm += next[i] * next[i];
    }
    norm = std::sqrt(norm);
    if (norm == 0) break;
    for (size_t i = 0; i < n; ++i) v[i] = next[i] / norm;
  }
  return v;
}

}  // namespace

absl::StatusOr<Pca2> PrincipalPlane(const std::vector<std::vector<float>>& rows) {
  if (rows.size() < 2) return absl::InvalidArgumentError("PCA: fewer than 2 z to project");
  const size_t n = rows[0].size();
  Pca2 pca;
  pca.mean.assign(n, 0.0);
  for (const auto& row : rows) {
    if (row.size() != n) return absl::InvalidArgumentError("PCA: z of different sizes");
    for (size_t i = 0; i < n; ++i) pca.mean[i] += row[i] / rows.size();
  }
  std::vector<double> cov(n * n, 0.0);
  for (const auto& row : rows) {
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < n; ++j) cov[i * n + j] += (row[i] - pca.mean[i]) * (row[j] - pca.mean[j]) / rows.size();
    }
  }
  double total = 0;
  for (size_t i = 0; i < n; ++i) total += cov[i * n + i];
  for (int k = 0; k < 2; ++k) {
    pca.axis[k] = LeadingAxis(cov, n);
    double lambda = 0;
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < n; ++j) lambda += pca.axis[k][i] * cov[i * n + j] * pca.axis[k][j];
    }
    pca.explained[k] = total > 0 ? lambda / total : 0.0;
    // Deflate, so that the next power iteration finds the second axis.
    for (size_t i = 0; i < n; ++i) {
      for (size_t j = 0; j < n; ++j) cov[i * n + j] -= lambda * pca.axis[k][i] * pca.axis[k][j];
    }
  }
  for (const auto& row : rows) {
    std::array<double, 2> point{0, 0};
    for (int k = 0; k < 2; ++k) {
      for (size_t i = 0; i < n; ++i) point[k] += (row[i] - pca.mean[i]) * pca.axis[k][i];
    }
    pca.points.push_back(point);
  }
  return pca;
}

absl::StatusOr<PartBodies> FindPartLayout(const std::vector<v1::EnvSpec>& layouts, int num_parts,
                                          const std::vector<std::string>& wanted) {
  for (const v1::EnvSpec& spec : layouts) {
    if (spec.parts_size() != num_parts) continue;
    PartBodies found;
    found.layout = spec.part_layout();
    for (const v1::BodyPart& part : spec.parts()) {
      found.names.push_back(part.name());
      std::vector<int> bodies;
      for (const std::string& body : part.bodies()) {
        const auto it = std::find(spec.body_names().begin(), spec.body_names().end(), body);
        if (it != spec.body_names().end()) bodies.push_back(static_cast<int>(it - spec.body_names().begin()));
      }
      found.bodies.push_back(std::move(bodies));
    }
    const bool has_all = std::all_of(wanted.begin(), wanted.end(), [&](const std::string& name) {
      return std::find(found.names.begin(), found.names.end(), name) != found.names.end();
    });
    if (has_all) return found;
  }
  return absl::NotFoundError(absl::StrCat("no part layout of the server has ", num_parts, " parts with those names"));
}

double Short(float value) {
  if (!std::isfinite(value)) return value;
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  *result.ptr = '\0';
  return std::strtod(buffer, nullptr);
}

nlohmann::ordered_json FloatRow(const std::vector<float>& values) {
  nlohmann::ordered_json row = nlohmann::ordered_json::array();
  for (float v : values) row.push_back(Short(v));
  return row;
}

}  // namespace modskill::cli
