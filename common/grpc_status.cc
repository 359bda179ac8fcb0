#include "common/grpc_status.h"

#include "absl/strings/str_cat.h"
#include "common/status_text.h"

namespace modskill {

absl::Status FromGrpcStatus(const grpc::Status& status, absl::string_view where) {
  if (status.ok()) return absl::OkStatus();
  return absl::Status(static_cast<absl::StatusCode>(status.error_code()),
                      absl::StrCat(where, ": ", status.error_message()));
}

grpc::Status ToGrpcStatus(const absl::Status& status) {
  if (status.ok()) return grpc::Status::OK;
  return CappedStatus(static_cast<grpc::StatusCode>(status.code()), status.message());
}

}  // namespace modskill
