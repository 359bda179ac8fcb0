#include "learner/address_resolver.h"

#include <arpa/inet.h>
#include <netdb.h>
#include <sys/socket.h>

#include <algorithm>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <thread>

#include "absl/strings/str_cat.h"

namespace modskill::learner {
namespace {

struct Lookup {
  std::mutex mutex;
  std::condition_variable done_cv;
  bool done = false;
  int error = 0;
  std::vector<std::string> v4, v6;
};

// Runs getaddrinfo and files the numeric addresses into `lookup`, by family.
void RunLookup(const std::string& host, int port, Lookup* lookup) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int error = getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  std::vector<std::string> v4, v6;
  for (addrinfo* a = found; error == 0 && a != nullptr; a = a->ai_next) {
    char text[INET6_ADDRSTRLEN] = {};
    if (a->ai_family == AF_INET) {
      inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ai_addr)->sin_addr, text, sizeof(text));
      v4.push_back(absl::StrCat(text, ":", port));
    } else if (a->ai_family == AF_INET6) {
      inet_ntop(AF_INET6, &reinterpret_cast<sockaddr_in6*>(a->ai_addr)->sin6_addr, text, sizeof(text));
      v6.push_back(absl::StrCat("[", text, "]:", port));
    }
  }
  if (found != nullptr) freeaddrinfo(found);
  std::lock_guard<std::mutex> lock(lookup->mutex);
  lookup->error = error;
  lookup->v4 = std::move(v4);
  lookup->v6 = std::move(v6);
  lookup->done = true;
  lookup->done_cv.notify_all();
}

}  // namespace

absl::StatusOr<std::vector<std::string>> ResolveTcpAddresses(const std::string& host, int port,
                                                             absl::Duration timeout) {
  // getaddrinfo has no timeout of its own (resolv.conf's retries can add up to a minute), so it
  // runs on a detached thread that owns the result jointly with this call.
  auto lookup = std::make_shared<Lookup>();
  std::thread([host, port, lookup] { RunLookup(host, port, lookup.get()); }).detach();
  std::unique_lock<std::mutex> lock(lookup->mutex);
  if (!lookup->done_cv.wait_for(lock, absl::ToChronoMilliseconds(timeout), [&] { return lookup->done; })) {
    return absl::DeadlineExceededError(
        absl::StrCat(host, ": the resolver gave no answer within ", absl::FormatDuration(timeout)));
  }
  if (lookup->error == EAI_NONAME || lookup->error == EAI_NODATA) {
    return absl::NotFoundError(absl::StrCat(host, ": the name resolves to no address (",
                                            gai_strerror(lookup->error), ")"));
  }
  if (lookup->error != 0) {
    return absl::UnavailableError(absl::StrCat(host, ": resolver error: ", gai_strerror(lookup->error)));
  }
  std::vector<std::string> addresses = lookup->v4.empty() ? lookup->v6 : lookup->v4;
  if (addresses.empty()) return absl::NotFoundError(absl::StrCat(host, ": the name resolves to no TCP address"));
  std::sort(addresses.begin(), addresses.end());
  addresses.erase(std::unique(addresses.begin(), addresses.end()), addresses.end());
  return addresses;
}

}  // namespace modskill::learner
