// libFuzzer target: the .npz reader (libzip's container and inflate, bounded by npz_reader.cc), the
// .npy parser (npy_reader.cc) and the AMASS importer.
// Inputs that start like a bare .npy go to ParseNpy; everything else is imported as an .npz.
#include <cstddef>
#include <cstdint>
#include <cstring>

#include "absl/strings/string_view.h"
#include "fuzz/fuzz_import.h"
#include "server/core/motion/npz_reader.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  modskill::fuzz::InitializeImportFuzzer();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size >= 6 && std::memcmp(data, "\x93NUMPY", 6) == 0) {
    (void)modskill::ParseNpy(absl::string_view(reinterpret_cast<const char*>(data), size), "fuzz.npy");
    return 0;
  }
  modskill::fuzz::FuzzImport(data, size, ".npz");
  return 0;
}
