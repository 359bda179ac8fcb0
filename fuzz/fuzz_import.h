// Shared body of the importer fuzz targets: the bytes go through the same path an AddMotions
// upload takes (a file with the format's extension, then ImportMotionFile), and an accepted clip
// must respect the resource limits.
#ifndef MODSKILL_FUZZ_FUZZ_IMPORT_H_
#define MODSKILL_FUZZ_FUZZ_IMPORT_H_

#include <cstddef>
#include <cstdint>

namespace modskill::fuzz {

// Lowers the limits so that long clips cost milliseconds, not seconds (the checks are the same),
// and loads the skeleton. Call from LLVMFuzzerInitialize.
void InitializeImportFuzzer();

// Imports `data` as a file ending in `extension` (".bvh", ".txt", ".npz", ".msclip") and aborts
// if an accepted clip breaks an invariant the importers promise.
void FuzzImport(const uint8_t* data, size_t size, const char* extension);

}  // namespace modskill::fuzz

#endif  // MODSKILL_FUZZ_FUZZ_IMPORT_H_
