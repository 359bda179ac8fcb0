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

// The k elites nearest u, nearest first, with their distances in the normalized space. An elite is
// clamped into the ranges first: its a was denormalized from [0, 1] and may overshoot a bound by
// a rounding error.
void AddNearestElites(const ParamSpace& space, const std::vector<FamilyEliteRecord>& elites,
                      const std::vector<double>& u, int k, v1::QueryFamilyResponse* out) {
  std::vector<std::pair<double, size_t>> by_distance;
  std::vector<double> inside;
  for (size_t e = 0; e < elites.size(); ++e) {
    inside = elites[e].params;
    for (size_t d = 0; d < inside.size() && d < space.ranges().size(); ++d) {
      inside[d] = std::clamp(inside[d], space.ranges()[d].lo, space.ranges()[d].hi);
    }
    const absl::StatusOr<std::vector<double>> v = space.Normalize(inside);
    if (!v.ok()) continue;  // another number of parameters: FamilyElitesFromJson refuses those
    double squared = 0;
    for (size_t d = 0; d < v->size(); ++d) squared += ((*v)[d] - u[d]) * ((*v)[d] - u[d]);
    by_distance.emplace_back(std::sqrt(squared), e);
  }
  const size_t count = std::min(by_distance.size(), static_cast<size_t>(k));
  std::partial_sort(by_distance.begin(), by_distance.begin() + count, by_distance.end());
  for (size_t i = 0; i < count; ++i) {
    const FamilyEliteRecord& elite = elites[by_distance[i].second];
    v1::FamilyElite* wire = out->add_nearest_elites();
    SetFamilyParams(space.ranges(), elite.params, wire->mutable_params());
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
  auto space = ParamSpace::Create(spec.family);  // the spec's ranges are checked (PolicySpec::FromJson)
  if (!space.ok()) return ToGrpcStatus(space.status());
  auto u = space->Normalize(*a);
  if (!u.ok()) return ToGrpcStatus(u.status());
  response->set_clip(spec.family_clip);
  for (const ParamRange& range : spec.family) {
    v1::FamilyParameterRange* wire = response->add_ranges();
    wire->set_name(range.name);
    wire->set_lo(range.lo);
    wire->set_hi(range.hi);
  }
  SetFamilyParams(spec.family, *a, response->mutable_params());
  for (double value : *u) response->add_normalized_params(value);
  if ((*policy)->has_parameterization()) {
    auto trajectory = (*policy)->Parameterization(*u);
    if (!trajectory.ok()) return ToGrpcStatus(trajectory.status());
    SetFloatTensor({spec.family_frames, spec.action_size}, trajectory->data(), response->mutable_parameterization());
    for (const std::string& joint : spec.joint_names) response->add_parameterization_columns(joint);
    response->add_parameterization_columns("tau");
  }
  response->set_elites(static_cast<int>((*policy)->family_elites().size()));
  AddNearestElites(*space, (*policy)->family_elites(), *u, nearest, response);
  return grpc::Status::OK;
}

}  // namespace modskill
