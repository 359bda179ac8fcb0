#include "server/service/session_registry.h"

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"

namespace modskill {

absl::StatusOr<std::string> SessionRegistry::Reserve() {
  absl::MutexLock lock(&mutex_);
  if (reserved_ >= max_sessions_) {
    return absl::ResourceExhaustedError(absl::StrCat("sessions: the server already runs ", reserved_,
                                                     " sessions (--max_sessions=", max_sessions_, ")"));
  }
  ++reserved_;
  return absl::StrCat("s", next_id_++);
}

void SessionRegistry::Release() {
  absl::MutexLock lock(&mutex_);
  --reserved_;
}

void SessionRegistry::Register(std::shared_ptr<SimulationSession> session) {
  absl::MutexLock lock(&mutex_);
  ++sessions_opened_;
  sessions_[session->id] = std::move(session);
}

void SessionRegistry::Close(const std::string& id) {
  absl::MutexLock lock(&mutex_);
  if (sessions_.erase(id) > 0) --reserved_;
}

std::shared_ptr<SimulationSession> SessionRegistry::Find(const std::string& id) const {
  absl::MutexLock lock(&mutex_);
  auto it = sessions_.find(id);
  return it == sessions_.end() ? nullptr : it->second;
}

void SessionRegistry::AddSteps(int64_t env_steps, int64_t episodes, int64_t physics_resets) {
  env_steps_ += env_steps;
  episodes_ += episodes;
  physics_resets_ += physics_resets;
}

ServerTotals SessionRegistry::Totals() {
  ServerTotals totals;
  const absl::Time now = absl::Now();
  absl::MutexLock lock(&mutex_);
  totals.active_sessions = static_cast<int>(sessions_.size());
  totals.sessions_opened = sessions_opened_;
  totals.env_steps = env_steps_;
  totals.episodes = episodes_;
  totals.physics_resets = physics_resets_;
  totals.failure_reports = failure_reports_;
  totals.uptime_seconds = absl::ToDoubleSeconds(now - started_);
  for (const auto& [id, session] : sessions_) totals.sessions.push_back(session);
  // Rate over the last ~10 s of GetStats calls (or since start on the first call).
  step_samples_.emplace_back(now, totals.env_steps);
  while (step_samples_.size() > 1 && now - step_samples_[1].first > absl::Seconds(10)) step_samples_.pop_front();
  const auto& [then, steps_then] = step_samples_.size() > 1 ? step_samples_.front() : std::make_pair(started_, int64_t{0});
  const double seconds = absl::ToDoubleSeconds(now - then);
  totals.env_steps_per_second = seconds > 0 ? (totals.env_steps - steps_then) / seconds : 0;
  return totals;
}

}  // namespace modskill
