// The test process's resident memory, for bounds on what one bad request may make an in-process
// server allocate: the peak is reset before the request (Linux: clear_refs "5") and read after it.
#ifndef MODSKILL_TESTS_PROCESS_MEMORY_H_
#define MODSKILL_TESTS_PROCESS_MEMORY_H_

#include <cstdint>
#include <fstream>
#include <string>

namespace modskill::testing {

// A "VmRSS:" / "VmHWM:" line of /proc/self/status, in bytes (0 when unreadable).
inline int64_t ProcStatusBytes(const std::string& key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind(key, 0) == 0) return std::stoll(line.substr(key.size())) * 1024;  // "  12345 kB"
  }
  return 0;
}

inline int64_t ResidentBytes() { return ProcStatusBytes("VmRSS:"); }
inline int64_t PeakResidentBytes() { return ProcStatusBytes("VmHWM:"); }

// Makes the peak start again from the current resident size.
inline void ResetPeakResident() { std::ofstream("/proc/self/clear_refs") << "5"; }

// Measures how far the peak rose above the resident size while `run` ran.
template <typename Run>
int64_t PeakGrowthBytes(Run&& run) {
  ResetPeakResident();
  const int64_t before = ResidentBytes();
  run();
  return PeakResidentBytes() - before;
}

}  // namespace modskill::testing

#endif  // MODSKILL_TESTS_PROCESS_MEMORY_H_
