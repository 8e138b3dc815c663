#include "binloop/io/filesystem.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "binloop/io/data_error.h"

namespace fs = std::filesystem;

namespace binloop {

void requireFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw dataError(path, 0, "no such file");
  if (fs::is_directory(path, ec)) throw dataError(path, 0, "is a folder, expected a file");
}

void requireDirectory(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw dataError(path, 0, "no such folder");
  if (!fs::is_directory(path, ec)) throw dataError(path, 0, "is a file, expected a folder");
}

bool naturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i]));
    const bool db = std::isdigit(static_cast<unsigned char>(b[j]));
    if (da && db) {
      size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      // Compare by value: strip leading zeros, then by length, then lexicographically.
      size_t is = i, js = j;
      while (is + 1 < ie && a[is] == '0') ++is;
      while (js + 1 < je && b[js] == '0') ++js;
      if (ie - is != je - js) return ie - is < je - js;
      const int c = a.compare(is, ie - is, b, js, je - js);
      if (c != 0) return c < 0;
      if (ie - i != je - j) return ie - i < je - j;  // "01" before "1"... keep order total
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

std::vector<std::string> listFilesNatural(const std::string& dir, const std::vector<std::string>& exts) {
  requireDirectory(dir);
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::string ext = e.path().extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    if (std::find(exts.begin(), exts.end(), ext) == exts.end()) continue;
    names.push_back(e.path().filename().string());
  }
  std::sort(names.begin(), names.end(), naturalLess);
  for (auto& n : names) n = (fs::path(dir) / n).string();
  return names;
}

}  // namespace binloop
