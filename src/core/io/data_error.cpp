#include "binloop/io/data_error.h"

namespace binloop {

DataError dataError(const std::string& path, int line, const std::string& what) {
  std::string where = path;
  if (line > 0) where += ":" + std::to_string(line);
  return DataError(where + ": " + what);
}

}  // namespace binloop
