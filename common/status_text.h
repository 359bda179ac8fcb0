// A status travels in the response's trailing metadata, which clients cap (8 KiB by default): a
// message that echoed a 20 KB session id or a 1 MB clip name failed on the client as
// RESOURCE_EXHAUSTED and took the channel's other calls with it. Values are shown bounded
// (core/shown_value.h), and every message the service returns is cut as a backstop.
#ifndef MODSKILL_COMMON_STATUS_TEXT_H_
#define MODSKILL_COMMON_STATUS_TEXT_H_

#include <cstddef>
#include <string>

#include <grpcpp/grpcpp.h>

#include "absl/strings/string_view.h"

namespace modskill {

inline constexpr size_t kMaxStatusMessageBytes = 1024;

// `message` cut to kMaxStatusMessageBytes on a UTF-8 boundary, with "... (N bytes)".
std::string CappedMessage(absl::string_view message);

// A gRPC status with a capped message.
grpc::Status CappedStatus(grpc::StatusCode code, absl::string_view message);

}  // namespace modskill

#endif  // MODSKILL_COMMON_STATUS_TEXT_H_
