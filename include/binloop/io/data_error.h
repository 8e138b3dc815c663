#pragma once
// The one exception type the io module throws: the message names the file (and line) and says what is
// wrong in words a user can act on. Library code throws; tools and nodelets catch and report.
#include <stdexcept>
#include <string>

namespace binloop {

class DataError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// "path:line: what" (line omitted when 0).
DataError dataError(const std::string& path, int line, const std::string& what);

}  // namespace binloop
