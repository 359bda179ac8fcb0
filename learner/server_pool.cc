#include "learner/server_pool.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/log.h"

namespace modskill::learner {

ServerPool::ServerPool(ServerPoolOptions options) : options_(std::move(options)) {
  for (const std::string& server : options_.servers) {
    for (int s = 0; s < options_.sessions_per_server; ++s) {
      auto slot = std::make_unique<SessionSlot>();
      slot->server = server;
      slot->index_on_server = s;
      slots_.push_back(std::move(slot));
    }
  }
}

absl::Status ServerPool::Open(SessionSlot* slot, int64_t seed) {
  if (slot->client == nullptr) {
    ClientOptions client;
    client.server = slot->server;
    client.token = options_.token;
    client.tls_ca_file = options_.tls_ca_file;
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
  config.set_seed(static_cast<uint64_t>(seed) * 7919 + slot->index_on_server * 104729 +
                  std::hash<std::string>()(slot->server) % 1000003);
  auto stream = slot->client->OpenSession(config);
  if (!stream.ok()) {
    slot->client.reset();  // a fresh channel next time
    return stream.status();
  }
  const v1::EnvSpec& spec = (*stream)->spec();
  if (!have_spec_) {
    spec_ = spec;
    have_spec_ = true;
  } else if (spec.obs_size() != spec_.obs_size() || spec.action_size() != spec_.action_size() ||
             spec.amp_obs_per_frame() != spec_.amp_obs_per_frame() || spec.part_layout() != spec_.part_layout()) {
    return absl::FailedPreconditionError(
        absl::StrCat(slot->server, ": env spec differs from the other servers' (obs ", spec.obs_size(), " vs ",
                     spec_.obs_size(), ", layout ", spec.part_layout(), " vs ", spec_.part_layout(), ")"));
  }
  slot->stream = *std::move(stream);
  ++slot->generation;
  return absl::OkStatus();
}

int ServerPool::Reconnect(int64_t seed) {
  const absl::Time now = absl::Now();
  for (auto& slot : slots_) {
    if (slot->alive || now < slot->retry_at) continue;
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
