#pragma once
// Reading text files made of lines of numbers (times.txt, poses, calib.txt, loop pairs): one parser so
// every file reports bad input the same way, with file and line.
#include <string>
#include <vector>

namespace binloop {

struct NumberLine {
  int line_no = 0;    // 1-based line in the file
  std::string label;  // "P0" for "P0: 1 2 3"; empty when the line has no "label:" prefix
  std::vector<double> values;
};

/// Reads `path`, skipping blank lines and lines starting with '#'. A token that is not a number throws
/// DataError("path:line: 'abc' is not a number"). A missing or unreadable file throws DataError too.
std::vector<NumberLine> readNumberLines(const std::string& path);

/// Checks that `l` holds exactly `n` values; throws DataError naming `what` otherwise.
void requireCount(const std::string& path, const NumberLine& l, size_t n, const std::string& what);

}  // namespace binloop
