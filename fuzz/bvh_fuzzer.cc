// libFuzzer target: CMU BVH (server/core/motion/bvh_parser.cc, bvh_import.cc), through ImportMotionFile.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_import.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  modskill::fuzz::InitializeImportFuzzer();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  modskill::fuzz::FuzzImport(data, size, ".bvh");
  return 0;
}
