// Where the shipped data (skeleton, part layouts, motion library) is found.
#ifndef MODSKILL_SERVER_CORE_UTIL_DATA_PATHS_H_
#define MODSKILL_SERVER_CORE_UTIL_DATA_PATHS_H_

#include <string>

namespace modskill {

// $MODSKILL_DATA when set, else the data directory of the source tree the binary was built from.
std::string DataDirectory();

// DataDirectory() joined with a relative path such as "skeleton/smpl24_skeleton.json".
std::string DataPath(const std::string& relative);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_UTIL_DATA_PATHS_H_
