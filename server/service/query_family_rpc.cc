// The QueryFamily RPC: a motor-skill family's policy.pt (learner/family/family_export.h) at task
// parameters a: its ranges, P(a) over the clip's frames and the elites nearest to a.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/grpc_status.h"
#include "common/wire/tensor_codec.h"
#include "server/service/family_request.h"
#include "server/service/simulation_service.h"

namespace modskill {
namespace {

constexpr int kDefaultNearestElites = 5;  // the paper's k
constexpr int kMaxNearestElites = 64;

// a over each range in [0, 1]; 0 for a constraint (ParamSpace::Normalize).
std::vector<double> Normalized(const std::vector<ParamRange>& ranges, const std::vector<double>& a) {
  std::vector<double> u;
  for (size_t k = 0; k < ranges.size(); ++k) {
    const double width = ranges[k].hi - ranges[k].lo;
    u.push_back(width > 0 ? (a[k] - ranges[k].lo) / width : 0.0);
  }
  return u;
}

// The k elites nearest u, nearest first, with their distances in the normalized space.
void AddNearestElites(const std::vector<ParamRange>& ranges, const std::vector<FamilyEliteRecord>& elites,
                      const std::vector<double>& u, int k, v1::QueryFamilyResponse* out) {
  std::vector<std::pair<double, size_t>> by_distance;
  for (size_t e = 0; e < elites.size(); ++e) {
    const std::vector<double> v = Normalized(ranges, elites[e].params);
    double squared = 0;
    for (size_t d = 0; d < v.size(); ++d) squared += (v[d] - u[d]) * (v[d] - u[d]);
    by_distance.emplace_back(std::sqrt(squared), e);
  }
  const size_t count = std::min(by_distance.size(), static_cast<size_t>(k));
  std::partial_sort(by_distance.begin(), by_distance.begin() + count, by_distance.end());
  for (size_t i = 0; i < count; ++i) {
    const FamilyEliteRecord& elite = elites[by_distance[i].second];
    v1::FamilyElite* wire = out->add_nearest_elites();
    SetFamilyParams(ranges, elite.params, wire->mutable_params());
    wire->set_fitness(elite.fitness);
    wire->set_distance(by_distance[i].first);
  }
}

}  // namespace

grpc::Status SimulationService::QueryFamily(grpc::ServerContext* context, const v1::QueryFamilyRequest* request,
                                            v1::QueryFamilyResponse* response) {
  if (auto auth = CheckAuth(context); !auth.ok()) return auth;
  const int nearest = request->nearest_elites() == 0 ? kDefaultNearestElites : request->nearest_elites();
  if (nearest < 0 || nearest > kMaxNearestElites) {
    return ToGrpcStatus(absl::InvalidArgumentError(
        absl::StrCat("nearest_elites: ", request->nearest_elites(), " is outside [0, ", kMaxNearestElites, "]")));
  }
  auto policy = LoadPolicy(request->has_checkpoint_path() ? &request->checkpoint_path() : nullptr,
                           request->has_checkpoint_bytes() ? &request->checkpoint_bytes() : nullptr);
  if (!policy.ok()) return ToGrpcStatus(policy.status());
  const PolicySpec& spec = (*policy)->spec();
  if (!spec.is_family()) {
    return ToGrpcStatus(absl::FailedPreconditionError(
        "checkpoint: not a motor-skill family's policy (modskill-learner --family exports one)"));
  }
  auto a = ResolveFamilyParams(spec.family, request->params(), "params");
  if (!a.ok()) return ToGrpcStatus(a.status());
  const std::vector<double> u = Normalized(spec.family, *a);
  response->set_clip(spec.family_clip);
  for (const ParamRange& range : spec.family) {
    v1::FamilyParameterRange* wire = response->add_ranges();
    wire->set_name(range.name);
    wire->set_lo(range.lo);
    wire->set_hi(range.hi);
  }
  SetFamilyParams(spec.family, *a, response->mutable_params());
  for (double value : u) response->add_normalized_params(value);
  if ((*policy)->has_parameterization()) {
    auto trajectory = (*policy)->Parameterization(u);
    if (!trajectory.ok()) return ToGrpcStatus(trajectory.status());
    SetFloatTensor({spec.family_frames, spec.action_size}, trajectory->data(), response->mutable_parameterization());
    for (const std::string& joint : spec.joint_names) response->add_parameterization_columns(joint);
    response->add_parameterization_columns("tau");
  }
  response->set_elites(static_cast<int>((*policy)->family_elites().size()));
  AddNearestElites(spec.family, (*policy)->family_elites(), u, nearest, response);
  return grpc::Status::OK;
}

}  // namespace modskill
