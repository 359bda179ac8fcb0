#include "client/cpp/family_command.h"

#include <cmath>
#include <cstdio>
#include <map>

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "client/cpp/checkpoint_source.h"
#include "client/cpp/cli_output.h"
#include "common/atomic_file.h"
#include "common/wire/tensor_codec.h"

namespace modskill::cli {
namespace {

using Json = nlohmann::ordered_json;

std::string ParamsText(const google::protobuf::Map<std::string, double>& params) {
  std::string text;
  for (const auto& [name, value] : std::map<std::string, double>(params.begin(), params.end())) {
    absl::StrAppend(&text, text.empty() ? "" : ", ", name, "=", value);
  }
  return text;
}

absl::StatusOr<v1::QueryFamilyRequest> MakeRequest(const FamilyQueryOptions& options) {
  v1::QueryFamilyRequest request;
  std::string shown;
  if (absl::Status status = SetCheckpoint(options.checkpoint, options.upload, &request, &shown); !status.ok()) return status;
  for (const auto& [name, value] : options.params) (*request.mutable_params())[name] = value;
  request.set_nearest_elites(options.nearest_elites);
  return request;
}

// P(a) as rows of the columns, and the clip's duration under its time warp (in clip frames
// played per frame: sum of exp(tau) over the frames' steps).
struct Parameterization {
  std::vector<std::vector<float>> rows;
  double mean_abs_displacement = 0;  // action units, over every hinge and frame
  double warped_steps = 0;           // control steps the warped clip takes: frames / mean exp(tau)
};

absl::StatusOr<Parameterization> ReadParameterization(const v1::QueryFamilyResponse& response) {
  Parameterization p;
  if (response.parameterization().shape_size() == 0) return p;
  std::vector<float> flat;
  if (absl::Status status = ReadFloatTensor(response.parameterization(), "parameterization", &flat); !status.ok()) {
    return status;
  }
  const size_t columns = response.parameterization_columns_size();
  if (columns < 2 || flat.size() % columns != 0) return absl::DataLossError("parameterization: does not match its columns");
  double phase_rate = 0;
  for (size_t r = 0; r * columns < flat.size(); ++r) {
    p.rows.emplace_back(flat.begin() + r * columns, flat.begin() + (r + 1) * columns);
    for (size_t c = 0; c + 1 < columns; ++c) p.mean_abs_displacement += std::abs(p.rows.back()[c]);
    phase_rate += std::exp(p.rows.back()[columns - 1]);
  }
  p.mean_abs_displacement /= p.rows.size() * (columns - 1);
  phase_rate /= p.rows.size();
  p.warped_steps = phase_rate > 0 ? (p.rows.size() - 1) / phase_rate : 0;
  return p;
}

Json ResponseJson(const v1::QueryFamilyResponse& response, const Parameterization& p) {
  Json ranges = Json::array();
  for (const v1::FamilyParameterRange& range : response.ranges()) {
    ranges.push_back({{"name", range.name()}, {"lo", range.lo()}, {"hi", range.hi()}});
  }
  Json elites = Json::array();
  for (const v1::FamilyElite& elite : response.nearest_elites()) {
    elites.push_back({{"params", std::map<std::string, double>(elite.params().begin(), elite.params().end())},
                      {"fitness", elite.fitness()},
                      {"distance", elite.distance()}});
  }
  return Json{{"clip", response.clip()},
              {"ranges", ranges},
              {"params", std::map<std::string, double>(response.params().begin(), response.params().end())},
              {"normalized_params", std::vector<double>(response.normalized_params().begin(), response.normalized_params().end())},
              {"elites", response.elites()},
              {"nearest_elites", elites},
              {"parameterization_columns", std::vector<std::string>(response.parameterization_columns().begin(),
                                                                     response.parameterization_columns().end())},
              {"parameterization", p.rows}};
}

}  // namespace

int QueryFamily(SimulationClient& client, const FamilyQueryOptions& options) {
  auto request = MakeRequest(options);
  if (!request.ok()) return Fail(request.status());
  auto response = client.QueryFamily(*request);
  if (!response.ok()) return Fail(response.status());
  auto p = ReadParameterization(*response);
  if (!p.ok()) return Fail(p.status());
  std::printf("family of %s at %s (%d elites in the set)\n", response->clip().c_str(),
              ParamsText(response->params()).c_str(), response->elites());
  for (const v1::FamilyParameterRange& range : response->ranges()) {
    std::printf("  %s in [%g, %g]\n", range.name().c_str(), range.lo(), range.hi());
  }
  for (const v1::FamilyElite& elite : response->nearest_elites()) {
    std::printf("  elite at %s: F %.3f, distance %.3f\n", ParamsText(elite.params()).c_str(), elite.fitness(),
                elite.distance());
  }
  if (p->rows.empty()) {
    std::printf("P(a): none yet (the run has fitted no parameterization network)\n");
  } else {
    std::printf("P(a): %zu frames x %zu columns; mean |displacement| %.3f (action units); the warped clip takes %.1f "
                "control steps\n",
                p->rows.size(), p->rows.front().size(), p->mean_abs_displacement, p->warped_steps);
  }
  if (options.out.empty()) return 0;
  const std::string text = ResponseJson(*response, *p).dump(1);
  if (absl::Status status = WriteFileAtomically(options.out, text + "\n"); !status.ok()) {
    return Fail(absl::StrCat("--out: ", status.message()));
  }
  std::printf("wrote %s: %s\n", options.out.c_str(), FormatBytes(text.size() + 1).c_str());
  return 0;
}

}  // namespace modskill::cli
