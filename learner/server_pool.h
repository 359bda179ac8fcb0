// The simulation servers one learner drives: a session per server (or two per server, each with
// half of its envs, so that one half steps while the learner computes the other's actions).
// A server that dies is dropped from the iteration, retried with exponential backoff, and
// rejoins when it answers again. The members come from server discovery (server_discovery.h),
// refreshed at each Reconnect: members that join get sessions, members that vanish are dropped.
#ifndef MODSKILL_LEARNER_SERVER_POOL_H_
#define MODSKILL_LEARNER_SERVER_POOL_H_

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "client/cpp/simulation_client.h"
#include "learner/server_discovery.h"

namespace modskill::learner {

struct ServerPoolOptions {
  std::vector<std::string> servers;  // --servers entries: host:port, dns:///name:port, file:///path
  std::string token;
  std::string tls_ca_file;
  int envs_per_server = 256;
  int sessions_per_server = 1;  // 2: split each server's envs in halves that overlap with inference
  v1::SessionConfig session;    // num_envs is set per session
  absl::Duration connect_timeout = absl::Seconds(3);
  absl::Duration max_backoff = absl::Seconds(30);
  DiscoveryOptions discovery;
};

struct SessionSlot {
  std::string server;
  std::string tls_server_name;  // a discovered member's DNS name, which its certificate must carry
  int index_on_server = 0;
  // The slot's place in the pool, fixed for its life: with the run's seed it fixes the seeds of the
  // slot's envs, so that a seed fixes a run whatever port or host its servers got.
  int pool_index = 0;
  // The server left the membership: no session, no retries; the slot is kept (the trainer keys its
  // bookkeeping by slot) and reused when a server joins.
  bool retired = false;
  std::unique_ptr<SimulationClient> client;
  std::unique_ptr<SimulationStream> stream;
  bool alive = false;
  absl::Time retry_at = absl::InfinitePast();
  absl::Duration backoff = absl::Seconds(1);
  int failures = 0;
  int64_t generation = 0;  // incremented every time a new session opens on this slot
  std::string last_error;
  absl::StatusCode last_code = absl::StatusCode::kOk;
  int num_envs() const { return stream ? stream->num_envs() : 0; }
};

class ServerPool {
 public:
  // INVALID_ARGUMENT for a bad --servers entry or server file (server_discovery.h).
  static absl::StatusOr<std::unique_ptr<ServerPool>> Create(ServerPoolOptions options);
  // FAILED_PRECONDITION naming `server` when its env differs from the first server's in sizes,
  // layout, control step or physics.
  static absl::Status CheckSameEnv(const std::string& server, const v1::EnvSpec& spec, const v1::EnvSpec& first);

  // Refreshes the membership, then opens every session that is due for a (re)try; returns how many
  // are alive. Call it only while no collection uses the slots (between iterations).
  int Reconnect(int64_t seed);
  // No session open and every server tried refused the session config itself (INVALID_ARGUMENT,
  // NOT_FOUND, FAILED_PRECONDITION: a bad field, an unknown clip or layout): that refusal, which
  // waiting will not cure; OK otherwise (a server down is still worth waiting for).
  absl::Status RefusedEverywhere() const;
  // Marks a slot dead after an error and schedules its retry.
  void MarkDead(SessionSlot* slot, const absl::Status& error);
  std::vector<SessionSlot*> Alive();
  std::vector<std::unique_ptr<SessionSlot>>& slots() { return slots_; }
  // The env spec of the first session that ever opened (all servers must agree).
  const v1::EnvSpec* spec() const { return have_spec_ ? &spec_ : nullptr; }
  int total_envs() const;
  // Why a --servers entry lists no server right now (a name that does not resolve, an unreadable
  // file), one line per entry; empty when every entry was read.
  std::vector<std::string> discovery_problems() const { return discovery_.problems(); }

 private:
  ServerPool(ServerPoolOptions options, ServerDiscovery discovery);
  absl::Status Open(SessionSlot* slot, int64_t seed);
  // Retires the slots of servers not in `members` and gives each new member its sessions.
  void UpdateMembers(const std::vector<ServerMember>& members);
  // A slot for session `index` of a joining server: its own retired one, another retired one, or new.
  SessionSlot* FreeSlot(const std::string& server, int index);

  ServerPoolOptions options_;
  ServerDiscovery discovery_;
  std::vector<std::unique_ptr<SessionSlot>> slots_;
  v1::EnvSpec spec_;
  bool have_spec_ = false;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_SERVER_POOL_H_
