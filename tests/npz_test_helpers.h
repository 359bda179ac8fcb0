// What the .npz and .npy reader tests share: float bytes, a one-member archive read back, and a
// check that a failure's message names what it must.
#ifndef MODSKILL_TESTS_NPZ_TEST_HELPERS_H_
#define MODSKILL_TESTS_NPZ_TEST_HELPERS_H_

#include <cstring>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "gtest/gtest.h"
#include "server/core/motion/npz_reader.h"
#include "tests/npz_test_writer.h"

namespace modskill::testing {

inline std::string ToBytes(const std::vector<float>& values) {
  std::string bytes(values.size() * sizeof(float), '\0');
  std::memcpy(bytes.data(), values.data(), bytes.size());  // The test host is little-endian.
  return bytes;
}

// Writes one member into an archive and reads the archive back.
inline absl::StatusOr<absl::flat_hash_map<std::string, NpyArray>> ReadSingleMember(
    const std::string& path, const std::string& member_name, const std::string& npy_bytes,
    bool compress = false) {
  NpzWriter writer;
  writer.AddRawMember(member_name, npy_bytes);
  EXPECT_TRUE(writer.Write(path, compress));
  return ReadNpz(path);
}

inline void ExpectFailureMentions(const absl::Status& status, const std::vector<std::string>& parts) {
  EXPECT_FALSE(status.ok());
  for (const std::string& part : parts) {
    EXPECT_TRUE(absl::StrContains(status.message(), part)) << "'" << part << "' not in: " << status;
  }
}

}  // namespace modskill::testing

#endif  // MODSKILL_TESTS_NPZ_TEST_HELPERS_H_
