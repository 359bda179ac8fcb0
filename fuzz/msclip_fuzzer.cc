// libFuzzer target: the native clip format (clip_file.cc), through ImportMotionFile.
// The trailing CRC-32 is recomputed over the mutated bytes: otherwise nearly every mutation
// stops at the checksum and the decoder behind it is never reached.
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz/fuzz_import.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  modskill::fuzz::InitializeImportFuzzer();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::vector<uint8_t> bytes(data, data + size);
  if (size >= 12) {
    const uint32_t crc = static_cast<uint32_t>(crc32(0L, bytes.data(), static_cast<uInt>(size - 4)));
    std::memcpy(bytes.data() + size - 4, &crc, 4);
  }
  modskill::fuzz::FuzzImport(bytes.data(), bytes.size(), ".msclip");
  return 0;
}
