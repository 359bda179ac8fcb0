#include "learner/server_pool.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/log.h"
#include "common/wire/physics_wire.h"

namespace modskill::learner {

ServerPool::ServerPool(ServerPoolOptions options, ServerDiscovery discovery)
    : options_(std::move(options)), discovery_(std::move(discovery)) {}

absl::StatusOr<std::unique_ptr<ServerPool>> ServerPool::Create(ServerPoolOptions options) {
  absl::StatusOr<ServerDiscovery> discovery = ServerDiscovery::Create(options.servers, options.discovery);
  if (!discovery.ok()) return discovery.status();
  return std::unique_ptr<ServerPool>(new ServerPool(std::move(options), *std::move(discovery)));
}

SessionSlot* ServerPool::FreeSlot(const std::string& server, int index) {
  SessionSlot* free = nullptr;
  for (auto& slot : slots_) {
    if (!slot->retired || slot->index_on_server != index) continue;
    if (slot->server == server) return slot.get();
    if (free == nullptr) free = slot.get();
  }
  if (free != nullptr) return free;
  slots_.push_back(std::make_unique<SessionSlot>());
  slots_.back()->index_on_server = index;
  slots_.back()->pool_index = static_cast<int>(slots_.size()) - 1;
  return slots_.back().get();
}

void ServerPool::UpdateMembers(const std::vector<ServerMember>& members) {
  std::set<std::string> wanted, present;
  for (const ServerMember& member : members) wanted.insert(member.address);
  for (auto& slot : slots_) {
    if (slot->retired) continue;
    if (wanted.count(slot->server) != 0) {
      present.insert(slot->server);
      continue;
    }
    if (slot->index_on_server == 0) LogLine("server %s: left the --servers membership, dropped", slot->server);
    slot->retired = true;
    slot->alive = false;
    slot->stream.reset();
    slot->client.reset();
  }
  for (const ServerMember& member : members) {
    if (!present.insert(member.address).second) continue;
    if (member.address != member.source) LogLine("server %s: joined (from --servers %s)", member.address, member.source);
    for (int s = 0; s < options_.sessions_per_server; ++s) {
      SessionSlot* slot = FreeSlot(member.address, s);
      slot->server = member.address;
      slot->tls_server_name = member.tls_server_name;
      slot->retired = false;
      slot->alive = false;
      slot->retry_at = absl::InfinitePast();
      slot->backoff = absl::Seconds(1);
      slot->failures = 0;
      slot->last_error.clear();
    }
  }
}

absl::Status ServerPool::Open(SessionSlot* slot, int64_t seed) {
  if (slot->client == nullptr) {
    ClientOptions client;
    client.server = slot->server;
    client.token = options_.token;
    client.tls_ca_file = options_.tls_ca_file;
    client.tls_server_name = slot->tls_server_name;
    client.connect_timeout = options_.connect_timeout;
    auto connected = SimulationClient::Connect(client);
    if (!connected.ok()) return connected.status();
    slot->client = *std::move(connected);
  }
  v1::SessionConfig config = options_.session;
  const int share = options_.envs_per_server / options_.sessions_per_server;
  config.set_num_envs(slot->index_on_server == options_.sessions_per_server - 1
                          ? options_.envs_per_server - share * (options_.sessions_per_server - 1)
                          : share);
  // Not the address: a server's port is often whatever was free, and the same seed would give
  // another run. Slots differ in pool_index, so no two sessions share env seeds.
  config.set_seed(static_cast<uint64_t>(seed) * 7919 + static_cast<uint64_t>(slot->pool_index) * 104729);
  auto stream = slot->client->OpenSession(config);
  if (!stream.ok()) {
    slot->client.reset();  // a fresh channel next time
    return stream.status();
  }
  const v1::EnvSpec& spec = (*stream)->spec();
  if (!have_spec_) {
    spec_ = spec;
    have_spec_ = true;
  } else if (absl::Status same = CheckSameEnv(slot->server, spec, spec_); !same.ok()) {
    return same;
  }
  slot->stream = *std::move(stream);
  ++slot->generation;
  return absl::OkStatus();
}

// One run's batch mixes every server's steps: they must be one env, down to the physics (a server
// started with another --substeps or --pd_gain_scale would silently train another controller).
absl::Status ServerPool::CheckSameEnv(const std::string& server, const v1::EnvSpec& spec, const v1::EnvSpec& first) {
  if (spec.obs_size() != first.obs_size() || spec.action_size() != first.action_size() ||
      spec.amp_obs_per_frame() != first.amp_obs_per_frame() || spec.part_layout() != first.part_layout()) {
    return absl::FailedPreconditionError(
        absl::StrCat(server, ": env spec differs from the other servers' (obs ", spec.obs_size(), " vs ",
                     first.obs_size(), ", layout ", spec.part_layout(), " vs ", first.part_layout(), ")"));
  }
  if (std::abs(spec.control_dt() - first.control_dt()) > 1e-9) {
    return absl::FailedPreconditionError(absl::StrCat(server, ": control_dt ", spec.control_dt(),
                                                      " s against the other servers' ", first.control_dt(), " s"));
  }
  if (std::string difference = PhysicsDifference(PhysicsOf(spec), PhysicsOf(first), "the other servers'");
      !difference.empty()) {
    return absl::FailedPreconditionError(absl::StrCat(server, ": simulates with ", difference));
  }
  return absl::OkStatus();
}

int ServerPool::Reconnect(int64_t seed) {
  UpdateMembers(discovery_.Refresh());
  const absl::Time now = absl::Now();
  for (auto& slot : slots_) {
    if (slot->retired || slot->alive || now < slot->retry_at) continue;
    if (absl::Status status = Open(slot.get(), seed); !status.ok()) {
      MarkDead(slot.get(), status);
      continue;
    }
    if (slot->failures > 0) LogLine("server %s: session %d back after %d failed tries", slot->server, slot->index_on_server, slot->failures);
    slot->alive = true;
    slot->failures = 0;
    slot->backoff = absl::Seconds(1);
  }
  return static_cast<int>(Alive().size());
}

absl::Status ServerPool::RefusedEverywhere() const {
  const SessionSlot* refused = nullptr;
  for (const auto& slot : slots_) {
    if (slot->retired) continue;
    const absl::StatusCode code = slot->last_code;
    const bool refusal = code == absl::StatusCode::kInvalidArgument || code == absl::StatusCode::kNotFound ||
                         code == absl::StatusCode::kFailedPrecondition;
    if (slot->alive || slot->failures == 0 || !refusal) return absl::OkStatus();
    refused = slot.get();
  }
  if (refused == nullptr) return absl::OkStatus();
  return absl::Status(refused->last_code, absl::StrCat("every server refused the session; ", refused->server, ": ",
                                                       refused->last_error));
}

void ServerPool::MarkDead(SessionSlot* slot, const absl::Status& error) {
  if (slot->alive || slot->failures == 0) {
    LogLine("server %s: session %d lost: %s (retrying with backoff)", slot->server, slot->index_on_server,
            error.message());
  }
  slot->alive = false;
  slot->stream.reset();
  // A fresh channel next time: a broken one waits out gRPC's own reconnect backoff first.
  slot->client.reset();
  slot->last_error = std::string(error.message());
  slot->last_code = error.code();
  ++slot->failures;
  slot->retry_at = absl::Now() + slot->backoff;
  slot->backoff = std::min(slot->backoff * 2, options_.max_backoff);
}

std::vector<SessionSlot*> ServerPool::Alive() {
  std::vector<SessionSlot*> alive;
  for (auto& slot : slots_) {
    if (slot->alive) alive.push_back(slot.get());
  }
  return alive;
}

int ServerPool::total_envs() const {
  int total = 0;
  for (const auto& slot : slots_) total += slot->alive ? slot->num_envs() : 0;
  return total;
}

}  // namespace modskill::learner
