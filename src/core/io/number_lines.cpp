#include "binloop/io/number_lines.h"

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "binloop/io/data_error.h"
#include "binloop/io/filesystem.h"

namespace binloop {

namespace {
bool parseDouble(const std::string& tok, double* out) {
  errno = 0;
  char* end = nullptr;
  *out = std::strtod(tok.c_str(), &end);
  return end != tok.c_str() && *end == '\0' && errno != ERANGE;
}
}  // namespace

std::vector<NumberLine> readNumberLines(const std::string& path) {
  requireFile(path);
  std::ifstream in(path);
  if (!in) throw dataError(path, 0, "cannot be opened for reading");
  std::vector<NumberLine> lines;
  std::string text;
  int line_no = 0;
  while (std::getline(in, text)) {
    ++line_no;
    if (!text.empty() && text.back() == '\r') text.pop_back();
    const auto first = text.find_first_not_of(" \t");
    if (first == std::string::npos || text[first] == '#') continue;
    NumberLine l;
    l.line_no = line_no;
    std::istringstream ss(text);
    std::string tok;
    bool first_tok = true;
    while (ss >> tok) {
      if (first_tok && tok.back() == ':') {
        l.label = tok.substr(0, tok.size() - 1);
        first_tok = false;
        continue;
      }
      first_tok = false;
      double v = 0;
      if (!parseDouble(tok, &v)) throw dataError(path, line_no, "'" + tok + "' is not a number");
      l.values.push_back(v);
    }
    lines.push_back(std::move(l));
  }
  if (in.bad()) throw dataError(path, line_no, "read error");
  return lines;
}

void requireCount(const std::string& path, const NumberLine& l, size_t n, const std::string& what) {
  if (l.values.size() != n) {
    throw dataError(
        path, l.line_no,
        what + " needs " + std::to_string(n) + " numbers, found " + std::to_string(l.values.size()));
  }
}

}  // namespace binloop
