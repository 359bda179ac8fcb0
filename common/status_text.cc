#include "common/status_text.h"

#include "absl/strings/str_cat.h"

namespace modskill {

std::string CappedMessage(absl::string_view message) {
  if (message.size() <= kMaxStatusMessageBytes) return std::string(message);
  // Cut on a UTF-8 character boundary: continuation bytes are 10xxxxxx.
  size_t end = kMaxStatusMessageBytes;
  while (end > 0 && (static_cast<unsigned char>(message[end]) & 0xC0) == 0x80) --end;
  return absl::StrCat(message.substr(0, end), "... (", message.size(), " bytes)");
}

grpc::Status CappedStatus(grpc::StatusCode code, absl::string_view message) {
  return grpc::Status(code, CappedMessage(message));
}

}  // namespace modskill
