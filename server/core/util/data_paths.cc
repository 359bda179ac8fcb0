#include "server/core/util/data_paths.h"

#include <cstdlib>

namespace modskill {

std::string DataDirectory() {
  const char* from_env = std::getenv("MODSKILL_DATA");
  if (from_env != nullptr && from_env[0] != '\0') return from_env;
  return MODSKILL_DEFAULT_DATA_DIR;
}

std::string DataPath(const std::string& relative) { return DataDirectory() + "/" + relative; }

}  // namespace modskill
