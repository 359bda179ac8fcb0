// Where the learner's simulation servers come from. Each --servers entry is one source:
//   host:port            one fixed server;
//   dns:///name:port     every address behind the name, re-resolved at each refresh (a headless
//                        Kubernetes service lists one address per ready pod);
//   file:///path         one host:port per line (# starts a comment), re-read when it changes.
// ServerPool refreshes at iteration boundaries: members that join get sessions from the next
// iteration, members that vanish are dropped.
#ifndef MODSKILL_LEARNER_SERVER_DISCOVERY_H_
#define MODSKILL_LEARNER_SERVER_DISCOVERY_H_

#include <sys/types.h>

#include <ctime>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"

namespace modskill::learner {

struct ServerMember {
  std::string address;          // host:port one channel connects to
  std::string tls_server_name;  // the name TLS certificates are checked against ("": the address's host)
  std::string source;           // the --servers entry it came from
};

struct ServerSource {
  enum class Kind { kFixed, kDns, kFile };
  Kind kind = Kind::kFixed;
  std::string spec;  // the entry as given
  std::string host;  // kFixed, kDns
  int port = 0;      // kFixed, kDns
  std::string path;  // kFile
};

// One --servers entry; INVALID_ARGUMENT naming --servers and the entry when it is none of the
// three forms (a port is required; dns:// with a DNS server authority is not supported).
absl::StatusOr<ServerSource> ParseServerSource(const std::string& spec);
// Every entry parses (no file is read).
absl::Status ValidateServerSpecs(const std::vector<std::string>& specs);
// A target for one gRPC channel to the first entry's server (--eval, a task run's Describe):
// host:port and dns:/// as given (gRPC resolves the name itself), a file's first address.
absl::StatusOr<std::string> FirstServerTarget(const std::vector<std::string>& specs);

struct DiscoveryOptions {
  absl::Duration resolve_timeout = absl::Seconds(5);        // one getaddrinfo call
  absl::Duration min_resolve_interval = absl::Seconds(1);  // between two lookups of one name
};

class ServerDiscovery {
 public:
  // Parses every entry and reads every file once: a bad entry, a file that cannot be read or a bad
  // line is INVALID_ARGUMENT naming --servers, the entry and the line. Names are not resolved yet.
  static absl::StatusOr<ServerDiscovery> Create(const std::vector<std::string>& specs,
                                                DiscoveryOptions options = DiscoveryOptions());

  // Re-reads files that changed and re-resolves names; returns every source's members (an
  // address listed twice counts once). A source that fails now keeps its last members and reports
  // the failure in problems() (logged once per change); a name that resolves to nothing has none.
  std::vector<ServerMember> Refresh();
  // One line per source whose last refresh failed, naming the entry; empty when all succeeded.
  std::vector<std::string> problems() const;

 private:
  struct FileStamp {
    timespec mtime{};
    off_t size = -1;
    ino_t inode = 0;
    bool operator==(const FileStamp& o) const {
      return mtime.tv_sec == o.mtime.tv_sec && mtime.tv_nsec == o.mtime.tv_nsec && size == o.size && inode == o.inode;
    }
  };
  struct SourceState {
    ServerSource source;
    std::vector<ServerMember> members;
    std::string problem;  // the last refresh's error, "" when it succeeded
    absl::Time last_lookup = absl::InfinitePast();
    FileStamp stamp;
  };
  absl::Status RefreshFile(SourceState* state);
  absl::Status RefreshDns(SourceState* state);

  DiscoveryOptions options_;
  std::vector<SourceState> sources_;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_SERVER_DISCOVERY_H_
