#pragma once
// What tests share: a temporary folder that cleans up after itself, and where ../shared/data is.
#include <gtest/gtest.h>

#include <string>

namespace binloop::test {

/// A fresh folder under the system temp dir, removed with its contents on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string operator/(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

/// `$BINLOOP_SHARED_DATA` or the ../shared/data beside the repository; `rel` is appended.
std::string sharedData(const std::string& rel = "");
bool exists(const std::string& path);
/// Writes `text` to `path` (creating parent folders).
void writeText(const std::string& path, const std::string& text);
/// The whole file; "" when it cannot be read.
std::string readText(const std::string& path);
/// Copies a file or a folder tree.
void copyTree(const std::string& from, const std::string& to);

/// Runs a shell command as a user would; its exit code and its stdout and stderr together.
struct CommandResult {
  int code;
  std::string out;
};
CommandResult runCommand(const std::string& command);

}  // namespace binloop::test

/// Skips the test (never passes it) when a file from ../shared/data is not there.
#define BINLOOP_REQUIRE_DATA(path)                                                         \
  do {                                                                                     \
    if (!::binloop::test::exists(path)) GTEST_SKIP() << "test data not found: " << (path); \
  } while (0)

/// Expects `stmt` to throw `Exc` whose what() contains `substr`.
#define EXPECT_THROW_WITH(stmt, Exc, substr)                                          \
  do {                                                                                \
    try {                                                                             \
      stmt;                                                                           \
      ADD_FAILURE() << #stmt " did not throw";                                        \
    } catch (const Exc& e) {                                                          \
      EXPECT_NE(std::string(e.what()).find(substr), std::string::npos)                \
          << "message was: " << e.what() << "\nexpected it to contain: " << (substr); \
    }                                                                                 \
  } while (0)
