// Training logs: TensorBoard event files and CSV, with no TensorFlow dependency.
//
// An event file is a sequence of TFRecords:
//   uint64 length (little-endian) | uint32 masked_crc32c(length bytes) |
//   payload (length bytes)        | uint32 masked_crc32c(payload)
// where each payload is a `tensorflow.Event` (proto/tensorboard/event.proto, the scalar subset).
// The first record carries file_version "brain.Event:2"; each scalar is one further record.
#ifndef MODSKILL_LEARNER_TENSORBOARD_WRITER_H_
#define MODSKILL_LEARNER_TENSORBOARD_WRITER_H_

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace modskill::learner {

// CRC-32C (Castagnoli, reflected polynomial 0x82F63B78), table-driven.
// Crc32c("123456789") == 0xE3069283.
uint32_t Crc32c(absl::string_view data);
// TFRecord's mask: ((crc >> 15) | (crc << 17)) + 0xa282ead8.
uint32_t MaskCrc32c(uint32_t crc);

// Appends scalars to `run_dir/events.out.tfevents.<unix seconds>.<hostname>`.
// Records are buffered until Flush(); the destructor flushes and closes the file.
// Not thread-safe: one writer per thread, or the caller serializes.
class TensorBoardWriter {
 public:
  // Creates `run_dir` if needed and writes the file_version record. Errors name the file.
  static absl::StatusOr<std::unique_ptr<TensorBoardWriter>> Open(const std::string& run_dir);
  ~TensorBoardWriter();
  TensorBoardWriter(const TensorBoardWriter&) = delete;
  TensorBoardWriter& operator=(const TensorBoardWriter&) = delete;

  // One Event{wall_time = now, step, summary{value{tag, simple_value = float(value)}}}.
  absl::Status AddScalar(const std::string& tag, int64_t step, double value);
  // Hands buffered records to the OS (fflush).
  absl::Status Flush();

  const std::string& path() const { return path_; }

 private:
  TensorBoardWriter(std::string path, std::FILE* file) : path_(std::move(path)), file_(file) {}
  absl::Status WriteRecord(absl::string_view payload);

  std::string path_;
  std::FILE* file_;
};

// A CSV table with a fixed header, one row per Append, flushed after each row.
class CsvLogger {
 public:
  // kAppend continues a resumed run's file; kFresh starts a new run's, replacing any old rows
  // (a fresh run in a used run directory must not draw its curve after the old run's).
  enum class Start { kAppend, kFresh };
  // A new (or empty) file gets the header `columns` joined by ','. With kAppend, an existing
  // file whose first line is that same header is appended to (a resumed run); any other header
  // is a FAILED_PRECONDITION naming the file and both headers. Column names may not contain
  // ',', '"' or newlines.
  static absl::StatusOr<std::unique_ptr<CsvLogger>> Open(const std::string& path,
                                                         const std::vector<std::string>& columns,
                                                         Start start = Start::kAppend);
  ~CsvLogger();
  CsvLogger(const CsvLogger&) = delete;
  CsvLogger& operator=(const CsvLogger&) = delete;

  // `row` must have one value per column; values are written in shortest round-trip form.
  absl::Status Append(const std::vector<double>& row);
  // One row of cells formatted by the caller (text columns, fixed precision); a cell may not
  // contain ',', '"' or a newline (INVALID_ARGUMENT naming the file and the column).
  absl::Status AppendCells(const std::vector<std::string>& cells);

  const std::string& path() const { return path_; }

 private:
  CsvLogger(std::string path, std::FILE* file, std::vector<std::string> columns)
      : path_(std::move(path)), file_(file), columns_(std::move(columns)) {}
  absl::Status WriteLine(const std::string& row);  // appends the newline

  std::string path_;
  std::FILE* file_;
  std::vector<std::string> columns_;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TENSORBOARD_WRITER_H_
