// gRPC and absl statuses, both ways: one place for the conversion every RPC caller and handler
// needs (the client, the learner's server pool, the external generator, the service).
#ifndef MODSKILL_COMMON_GRPC_STATUS_H_
#define MODSKILL_COMMON_GRPC_STATUS_H_

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace modskill {

// The same code, the message prefixed with `where` (e.g. "127.0.0.1:50051 Describe").
absl::Status FromGrpcStatus(const grpc::Status& status, absl::string_view where);

// The same code, the message capped (status_text.h): statuses travel in trailing metadata.
grpc::Status ToGrpcStatus(const absl::Status& status);

}  // namespace modskill

#endif  // MODSKILL_COMMON_GRPC_STATUS_H_
