#include "learner/server_discovery.h"

#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "common/log.h"
#include "learner/address_resolver.h"

namespace modskill::learner {
namespace {

constexpr int64_t kMaxServerFileBytes = 1 << 20;  // a list of addresses, not a data file

absl::Status BadEntry(absl::string_view spec, absl::string_view why) {
  return absl::InvalidArgumentError(absl::StrCat("--servers ", spec, ": ", why));
}

bool IsHostChar(char c) { return absl::ascii_isalnum(c) || c == '.' || c == '-' || c == '_'; }

// host:port or [ipv6]:port; fills host (brackets kept, as gRPC wants them) and port.
absl::Status SplitHostPort(absl::string_view text, std::string* host, int* port) {
  size_t colon = text.rfind(':');
  if (colon == absl::string_view::npos || colon == 0) return absl::InvalidArgumentError("expected host:port");
  absl::string_view h = text.substr(0, colon);
  if (h.front() == '[') {
    if (h.back() != ']' || h.size() < 3) return absl::InvalidArgumentError("expected [ipv6]:port");
  } else {
    for (char c : h) {
      if (!IsHostChar(c)) return absl::InvalidArgumentError(absl::StrCat("expected host:port (bad character '", std::string(1, c), "' in the host)"));
    }
  }
  if (!absl::SimpleAtoi(text.substr(colon + 1), port) || *port < 1 || *port > 65535) {
    return absl::InvalidArgumentError("the port must be a number in [1, 65535]");
  }
  *host = std::string(h);
  return absl::OkStatus();
}

// The addresses of a server file: one host:port per line, '#' comments, blank lines.
absl::StatusOr<std::vector<std::string>> ReadServerFile(const std::string& spec, const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return BadEntry(spec, absl::StrCat("cannot read ", path));
  std::stringstream text;
  text << in.rdbuf();
  if (text.str().size() > static_cast<size_t>(kMaxServerFileBytes)) {
    return BadEntry(spec, absl::StrCat(path, " is over ", kMaxServerFileBytes, " bytes"));
  }
  std::vector<std::string> addresses;
  int line_number = 0;
  for (absl::string_view line : absl::StrSplit(text.str(), '\n')) {
    ++line_number;
    line = absl::StripAsciiWhitespace(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    std::string host;
    int port = 0;
    if (absl::Status status = SplitHostPort(line, &host, &port); !status.ok()) {
      return BadEntry(spec, absl::StrCat(path, ":", line_number, ": '", line.substr(0, 64), "': ", status.message()));
    }
    addresses.push_back(std::string(line));
  }
  return addresses;
}

}  // namespace

absl::StatusOr<ServerSource> ParseServerSource(const std::string& spec) {
  ServerSource source;
  source.spec = spec;
  absl::string_view rest = spec;
  if (absl::ConsumePrefix(&rest, "file://")) {
    if (!absl::StartsWith(rest, "/")) return BadEntry(spec, "expected file:///absolute/path");
    source.kind = ServerSource::Kind::kFile;
    source.path = std::string(rest);
    return source;
  }
  if (absl::ConsumePrefix(&rest, "dns:")) {
    if (!absl::ConsumePrefix(&rest, "///")) {
      return BadEntry(spec, "expected dns:///name:port (a DNS server authority, dns://server/..., is not supported)");
    }
    source.kind = ServerSource::Kind::kDns;
  } else if (absl::StrContains(spec, "://") || absl::StartsWith(spec, "unix:") || absl::StartsWith(spec, "ipv4:")) {
    return BadEntry(spec, "unknown scheme (expected host:port, dns:///name:port or file:///path)");
  }
  if (absl::Status status = SplitHostPort(rest, &source.host, &source.port); !status.ok()) {
    return BadEntry(spec, status.message());
  }
  return source;
}

absl::Status ValidateServerSpecs(const std::vector<std::string>& specs) {
  for (const std::string& spec : specs) {
    if (absl::StatusOr<ServerSource> source = ParseServerSource(spec); !source.ok()) return source.status();
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> FirstServerTarget(const std::vector<std::string>& specs) {
  if (specs.empty()) return absl::InvalidArgumentError("--servers: no server given");
  absl::StatusOr<ServerSource> source = ParseServerSource(specs.front());
  if (!source.ok()) return source.status();
  if (source->kind != ServerSource::Kind::kFile) return source->spec;
  absl::StatusOr<std::vector<std::string>> addresses = ReadServerFile(source->spec, source->path);
  if (!addresses.ok()) return addresses.status();
  if (addresses->empty()) return BadEntry(source->spec, absl::StrCat(source->path, " lists no server"));
  return addresses->front();
}

absl::StatusOr<ServerDiscovery> ServerDiscovery::Create(const std::vector<std::string>& specs,
                                                        DiscoveryOptions options) {
  if (specs.empty()) return absl::InvalidArgumentError("--servers: no server given");
  ServerDiscovery discovery;
  discovery.options_ = options;
  for (const std::string& spec : specs) {
    absl::StatusOr<ServerSource> source = ParseServerSource(spec);
    if (!source.ok()) return source.status();
    SourceState state;
    state.source = *std::move(source);
    if (state.source.kind == ServerSource::Kind::kFixed) {
      state.members.push_back(ServerMember{absl::StrCat(state.source.host, ":", state.source.port), "", spec});
    } else if (state.source.kind == ServerSource::Kind::kFile) {
      // A file that is not there at the start is a mistake, not a membership change.
      if (absl::Status status = discovery.RefreshFile(&state); !status.ok()) return status;
    }
    discovery.sources_.push_back(std::move(state));
  }
  return discovery;
}

absl::Status ServerDiscovery::RefreshFile(SourceState* state) {
  struct stat info {};
  if (stat(state->source.path.c_str(), &info) != 0) {
    return BadEntry(state->source.spec, absl::StrCat("cannot read ", state->source.path, ": ", std::strerror(errno)));
  }
  const FileStamp stamp{info.st_mtim, info.st_size, info.st_ino};
  if (stamp == state->stamp) return absl::OkStatus();
  absl::StatusOr<std::vector<std::string>> addresses = ReadServerFile(state->source.spec, state->source.path);
  if (!addresses.ok()) return addresses.status();
  state->members.clear();
  for (std::string& address : *addresses) {
    state->members.push_back(ServerMember{std::move(address), "", state->source.spec});
  }
  state->stamp = stamp;
  return absl::OkStatus();
}

absl::Status ServerDiscovery::RefreshDns(SourceState* state) {
  const absl::Time now = absl::Now();
  if (now - state->last_lookup < options_.min_resolve_interval) {
    return state->problem.empty() ? absl::OkStatus() : absl::UnavailableError(state->problem);
  }
  state->last_lookup = now;
  absl::StatusOr<std::vector<std::string>> addresses =
      ResolveTcpAddresses(state->source.host, state->source.port, options_.resolve_timeout);
  if (!addresses.ok()) {
    // A name that now lists nothing (every pod gone) has no members; a resolver that fails or
    // does not answer says nothing about them, so they stay.
    if (addresses.status().code() == absl::StatusCode::kNotFound) state->members.clear();
    return absl::Status(addresses.status().code(),
                        absl::StrCat("--servers ", state->source.spec, ": ", addresses.status().message()));
  }
  state->members.clear();
  for (std::string& address : *addresses) {
    // Each member is dialled by address; TLS still checks the certificate against the name.
    state->members.push_back(ServerMember{std::move(address), state->source.host, state->source.spec});
  }
  return absl::OkStatus();
}

std::vector<ServerMember> ServerDiscovery::Refresh() {
  std::vector<ServerMember> members;
  std::set<std::string> seen;
  for (SourceState& state : sources_) {
    absl::Status status = absl::OkStatus();
    if (state.source.kind == ServerSource::Kind::kFile) status = RefreshFile(&state);
    if (state.source.kind == ServerSource::Kind::kDns) status = RefreshDns(&state);
    const std::string problem(status.message());
    if (problem != state.problem) {
      if (!problem.empty() && state.members.empty()) LogLine("%s (no server from it)", problem);
      if (!problem.empty() && !state.members.empty()) {
        LogLine("%s (keeping its last %d server(s))", problem, static_cast<int>(state.members.size()));
      }
      if (problem.empty()) LogLine("--servers %s: read again", state.source.spec);
      state.problem = problem;
    }
    for (const ServerMember& member : state.members) {
      if (seen.insert(member.address).second) members.push_back(member);
    }
  }
  return members;
}

std::vector<std::string> ServerDiscovery::problems() const {
  std::vector<std::string> problems;
  for (const SourceState& state : sources_) {
    if (!state.problem.empty()) problems.push_back(state.problem);
  }
  return problems;
}

}  // namespace modskill::learner
