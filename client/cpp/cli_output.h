// What every modskill-client command shares when it reports: the error line and exit code of a
// failed command, and byte counts for people.
#ifndef MODSKILL_CLIENT_CPP_CLI_OUTPUT_H_
#define MODSKILL_CLIENT_CPP_CLI_OUTPUT_H_

#include <cstddef>
#include <string>

#include "absl/status/status.h"

namespace modskill::cli {

// The exit code of a command that failed at run time (a usage error exits with 2).
constexpr int kRuntimeError = 1;

// Prints "error: <message>" to stderr and returns kRuntimeError.
int Fail(const absl::Status& status);
int Fail(const std::string& message);

// "512 B", "1.5 KiB (1536 B)", "2.0 MiB (2097152 B)".
std::string FormatBytes(size_t bytes);

}  // namespace modskill::cli

#endif  // MODSKILL_CLIENT_CPP_CLI_OUTPUT_H_
