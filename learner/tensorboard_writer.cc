#include "learner/tensorboard_writer.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/strings/str_split.h"
#include "common/atomic_file.h"
#include "tensorboard/event.pb.h"

namespace modskill::learner {
namespace {

constexpr std::array<uint32_t, 256> MakeCrc32cTable() {
  std::array<uint32_t, 256> table{};
  for (uint32_t i = 0; i < 256; ++i) {
    uint32_t crc = i;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) ? (crc >> 1) ^ 0x82F63B78u : crc >> 1;
    table[i] = crc;
  }
  return table;
}
constexpr std::array<uint32_t, 256> kCrc32cTable = MakeCrc32cTable();

void AppendLittleEndian(uint64_t bits, int num_bytes, std::string* out) {
  for (int i = 0; i < num_bytes; ++i) out->push_back(static_cast<char>((bits >> (8 * i)) & 0xFF));
}

double WallTimeSeconds() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// A failed C stdio / iostream call as a Status naming the file; never OK, even when the
// call left errno at 0.
absl::Status IoError(absl::string_view what) {
  const int error = errno;
  return error != 0 ? absl::ErrnoToStatus(error, what) : absl::UnknownError(what);
}

std::string HostName() {
  char name[256] = {};
  if (gethostname(name, sizeof(name) - 1) != 0 || name[0] == '\0') return "localhost";
  return name;
}

}  // namespace

uint32_t Crc32c(absl::string_view data) {
  uint32_t crc = 0xFFFFFFFFu;
  for (unsigned char byte : data) crc = kCrc32cTable[(crc ^ byte) & 0xFF] ^ (crc >> 8);
  return ~crc;
}

uint32_t MaskCrc32c(uint32_t crc) { return ((crc >> 15) | (crc << 17)) + 0xa282ead8u; }

// ---------------------------------------------------------------------------------------------
// TensorBoardWriter

absl::StatusOr<std::unique_ptr<TensorBoardWriter>> TensorBoardWriter::Open(
    const std::string& run_dir) {
  std::error_code error;
  std::filesystem::create_directories(run_dir, error);
  if (error) {
    return absl::FailedPreconditionError(
        absl::StrCat("TensorBoard run directory ", run_dir, ": ", error.message()));
  }
  const auto seconds = static_cast<int64_t>(WallTimeSeconds());
  const std::string base =
      (std::filesystem::path(run_dir) / absl::StrCat("events.out.tfevents.", seconds, ".",
                                                     HostName()))
          .string();
  // Exclusive create ("x"), so two writers opened in the same second never share a file.
  std::string path = base;
  std::FILE* file = nullptr;
  for (int suffix = 1; suffix <= 100; ++suffix) {
    file = std::fopen(path.c_str(), "wbx");
    if (file != nullptr || errno != EEXIST) break;
    path = absl::StrCat(base, ".", suffix);
  }
  if (file == nullptr) return IoError(absl::StrCat("open ", path));

  std::unique_ptr<TensorBoardWriter> writer(new TensorBoardWriter(path, file));
  tensorflow::Event event;
  event.set_wall_time(WallTimeSeconds());
  event.set_file_version("brain.Event:2");
  if (absl::Status status = writer->WriteRecord(event.SerializeAsString()); !status.ok()) return status;
  if (absl::Status status = writer->Flush(); !status.ok()) return status;
  return writer;
}

TensorBoardWriter::~TensorBoardWriter() { std::fclose(file_); }

absl::Status TensorBoardWriter::AddScalar(const std::string& tag, int64_t step, double value) {
  tensorflow::Event event;
  event.set_wall_time(WallTimeSeconds());
  event.set_step(step);
  tensorflow::Summary::Value* scalar = event.mutable_summary()->add_value();
  scalar->set_tag(tag);
  scalar->set_simple_value(static_cast<float>(value));
  return WriteRecord(event.SerializeAsString());
}

absl::Status TensorBoardWriter::Flush() {
  if (std::fflush(file_) != 0) return IoError(absl::StrCat("flush ", path_));
  return absl::OkStatus();
}

absl::Status TensorBoardWriter::WriteRecord(absl::string_view payload) {
  std::string record;
  record.reserve(payload.size() + 16);
  AppendLittleEndian(payload.size(), 8, &record);
  AppendLittleEndian(MaskCrc32c(Crc32c(record)), 4, &record);
  record.append(payload.data(), payload.size());
  AppendLittleEndian(MaskCrc32c(Crc32c(payload)), 4, &record);
  if (std::fwrite(record.data(), 1, record.size(), file_) != record.size()) {
    return IoError(absl::StrCat("write ", path_));
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------------------------
// CsvLogger

namespace {

// Rewrites the CSV at `path` (header `old_header`) under `new_header`, which extends it by
// columns at the end; existing rows get empty values there. Atomic: a crash keeps the old file.
absl::Status AppendColumns(const std::string& path, const std::string& old_header, const std::string& new_header) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream rows;
  rows << in.rdbuf();
  std::string text = rows.str();
  const size_t body = text.find('\n');
  const std::string padding(std::count(new_header.begin() + old_header.size(), new_header.end(), ','), ',');
  std::string upgraded = new_header + "\n";
  if (body != std::string::npos) {
    for (absl::string_view line : absl::StrSplit(absl::string_view(text).substr(body + 1), '\n', absl::SkipEmpty())) {
      if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
      absl::StrAppend(&upgraded, line, padding, "\n");
    }
  }
  return WriteFileAtomically(path, upgraded);
}

}  // namespace

absl::StatusOr<std::unique_ptr<CsvLogger>> CsvLogger::Open(
    const std::string& path, const std::vector<std::string>& columns, Start start) {
  if (columns.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("CSV log ", path, ": no columns"));
  }
  for (const std::string& column : columns) {
    if (column.empty() || column.find_first_of(",\"\r\n") != std::string::npos) {
      return absl::InvalidArgumentError(
          absl::StrCat("CSV log ", path, ": bad column name '", column, "'"));
    }
  }
  const std::string header = absl::StrJoin(columns, ",");

  // An existing, non-empty file must start with the same header (a resumed run).
  bool write_header = true;
  bool needs_newline = false;
  std::error_code error;
  if (start == Start::kAppend && std::filesystem::exists(path, error) && std::filesystem::file_size(path, error) > 0 &&
      !error) {
    std::ifstream in(path, std::ios::binary);
    std::string first_line;
    if (!in || !std::getline(in, first_line)) {
      return IoError(absl::StrCat("read ", path));
    }
    if (!first_line.empty() && first_line.back() == '\r') first_line.pop_back();
    if (first_line != header && absl::StartsWith(header, first_line + ",")) {
      // A run from an older version, with fewer columns: its rows get empty new columns.
      if (absl::Status status = AppendColumns(path, first_line, header); !status.ok()) return status;
      first_line = header;
    }
    if (first_line != header) {
      return absl::FailedPreconditionError(absl::StrCat("CSV log ", path, " has header '",
                                                        first_line, "', expected '", header,
                                                        "'"));
    }
    // A run that died mid-row leaves no trailing newline; start the next row on its own line.
    in.clear();
    in.seekg(-1, std::ios::end);
    needs_newline = in.get() != '\n';
    write_header = false;
  }

  std::FILE* file = std::fopen(path.c_str(), start == Start::kFresh ? "wb" : "ab");
  if (file == nullptr) return IoError(absl::StrCat("open ", path));
  std::unique_ptr<CsvLogger> logger(new CsvLogger(path, file, columns));
  std::string text = needs_newline ? "\n" : "";
  if (write_header) absl::StrAppend(&text, header, "\n");
  if (!text.empty() &&
      (std::fwrite(text.data(), 1, text.size(), file) != text.size() || std::fflush(file) != 0)) {
    return IoError(absl::StrCat("write ", path));
  }
  return logger;
}

CsvLogger::~CsvLogger() { std::fclose(file_); }

absl::Status CsvLogger::Append(const std::vector<double>& row) {
  if (row.size() != columns_.size()) {
    return absl::InvalidArgumentError(absl::StrCat("CSV log ", path_, ": row has ", row.size(),
                                                   " values, header has ", columns_.size()));
  }
  std::string line;
  char number[32];
  for (size_t i = 0; i < row.size(); ++i) {
    if (i > 0) line.push_back(',');
    const auto result = std::to_chars(number, number + sizeof(number), row[i]);  // shortest
    line.append(number, result.ptr);
  }
  return WriteLine(line);
}

absl::Status CsvLogger::AppendCells(const std::vector<std::string>& cells) {
  if (cells.size() != columns_.size()) {
    return absl::InvalidArgumentError(absl::StrCat("CSV log ", path_, ": row has ", cells.size(),
                                                   " cells, header has ", columns_.size()));
  }
  for (size_t i = 0; i < cells.size(); ++i) {
    if (cells[i].find_first_of(",\"\r\n") != std::string::npos) {
      return absl::InvalidArgumentError(
          absl::StrCat("CSV log ", path_, ": column ", columns_[i], ": cell '", cells[i], "' holds a separator"));
    }
  }
  return WriteLine(absl::StrJoin(cells, ","));
}

absl::Status CsvLogger::WriteLine(const std::string& row) {
  const std::string line = row + "\n";
  if (std::fwrite(line.data(), 1, line.size(), file_) != line.size() || std::fflush(file_) != 0) {
    return IoError(absl::StrCat("write ", path_));
  }
  return absl::OkStatus();
}

}  // namespace modskill::learner
