// The simulation servers one learner drives: a session per server (or two per server, each with
// half of its envs, so that one half steps while the learner computes the other's actions).
// A server that dies is dropped from the iteration, retried with exponential backoff, and
// rejoins when it answers again.
#ifndef MODSKILL_LEARNER_SERVER_POOL_H_
#define MODSKILL_LEARNER_SERVER_POOL_H_

#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "client/cpp/simulation_client.h"

namespace modskill::learner {

struct ServerPoolOptions {
  std::vector<std::string> servers;  // host:port
  std::string token;
  std::string tls_ca_file;
  int envs_per_server = 256;
  int sessions_per_server = 1;  // 2: split each server's envs in halves that overlap with inference
  v1::SessionConfig session;    // num_envs is set per session
  absl::Duration connect_timeout = absl::Seconds(3);
  absl::Duration max_backoff = absl::Seconds(30);
};

struct SessionSlot {
  std::string server;
  int index_on_server = 0;
  std::unique_ptr<SimulationClient> client;
  std::unique_ptr<SimulationStream> stream;
  bool alive = false;
  absl::Time retry_at = absl::InfinitePast();
  absl::Duration backoff = absl::Seconds(1);
  int failures = 0;
  int64_t generation = 0;  // incremented every time a new session opens on this slot
  std::string last_error;
  int num_envs() const { return stream ? stream->num_envs() : 0; }
};

class ServerPool {
 public:
  explicit ServerPool(ServerPoolOptions options);

  // Opens every session that is due for a (re)try; returns how many are alive.
  int Reconnect(int64_t seed);
  // Marks a slot dead after an error and schedules its retry.
  void MarkDead(SessionSlot* slot, const absl::Status& error);
  std::vector<SessionSlot*> Alive();
  std::vector<std::unique_ptr<SessionSlot>>& slots() { return slots_; }
  // The env spec of the first session that ever opened (all servers must agree).
  const v1::EnvSpec* spec() const { return have_spec_ ? &spec_ : nullptr; }
  int total_envs() const;

 private:
  absl::Status Open(SessionSlot* slot, int64_t seed);

  ServerPoolOptions options_;
  std::vector<std::unique_ptr<SessionSlot>> slots_;
  v1::EnvSpec spec_;
  bool have_spec_ = false;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_SERVER_POOL_H_
