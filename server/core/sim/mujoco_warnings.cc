#include "server/core/sim/mujoco_warnings.h"

#include <mujoco/mujoco.h>

#include <map>
#include <mutex>
#include <string>

#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "common/log.h"

namespace modskill {
namespace {

constexpr absl::Duration kRepeatInterval = absl::Seconds(10);

struct Repeats {
  absl::Time last_logged = absl::InfinitePast();
  long long suppressed = 0;
};

void LogMujocoWarning(const char* message) {
  static std::mutex mutex;
  static std::map<std::string, Repeats> seen;
  const std::string text(message != nullptr ? message : "");
  const absl::Time now = absl::Now();
  std::lock_guard<std::mutex> lock(mutex);
  Repeats& repeats = seen[text.substr(0, 200)];
  if (now - repeats.last_logged < kRepeatInterval) {
    ++repeats.suppressed;
    return;
  }
  if (repeats.suppressed > 0) {
    LogLine("MuJoCo warning: %s (and %lld more times since it was last logged)", text, repeats.suppressed);
  } else {
    LogLine("MuJoCo warning: %s", text);
  }
  repeats.last_logged = now;
  repeats.suppressed = 0;
}

}  // namespace

void RouteMujocoWarningsToLog() {
  static std::once_flag once;
  std::call_once(once, [] { mju_user_warning = LogMujocoWarning; });
}

}  // namespace modskill
