#pragma once
// Small file-system checks that throw DataError with a message a user can act on.
#include <string>
#include <vector>

namespace binloop {

void requireFile(const std::string& path);       // "…: no such file" / "…: is a directory"
void requireDirectory(const std::string& path);  // "…: no such folder"
/// Files in `dir` whose extension (lower-cased, with dot) is one of `exts`, in natural order
/// ("2.png" before "10.png"). Throws DataError if `dir` is missing.
std::vector<std::string> listFilesNatural(const std::string& dir, const std::vector<std::string>& exts);
/// "a2b10" < "a10b2"? Compares digit runs by value, the rest byte-wise.
bool naturalLess(const std::string& a, const std::string& b);

}  // namespace binloop
