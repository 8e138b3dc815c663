#include "binloop/util/package_paths.h"

#include <dlfcn.h>

#include <cstdlib>
#include <filesystem>
#include <system_error>

namespace binloop {

namespace fs = std::filesystem;

namespace {

bool holdsVocab(const fs::path& dir) {
  std::error_code ec;
  return !dir.empty() && fs::is_directory(dir / "vocab", ec);
}

// catkin installs libraries to <prefix>/lib/, programs to <prefix>/lib/binloop/ and data to
// <prefix>/share/binloop/: from where this library or the running program lies to the data.
fs::path shareBeside(const fs::path& lib_dir) { return lib_dir.parent_path() / "share" / "binloop"; }

}  // namespace

std::string packageDir() {
  if (const char* env = std::getenv("BINLOOP_PACKAGE_DIR"); env && *env) return env;
  Dl_info info{};
  if (dladdr(reinterpret_cast<const void*>(&packageDir), &info) && info.dli_fname) {
    const fs::path share = shareBeside(fs::path(info.dli_fname).parent_path());
    if (holdsVocab(share)) return share.string();
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const fs::path share = shareBeside(exe.parent_path().parent_path());
    if (holdsVocab(share)) return share.string();
  }
  return BINLOOP_SOURCE_DIR;
}

std::string packagePath(const std::string& rel) { return (fs::path(packageDir()) / rel).string(); }

std::string modelDirFor(const std::string& given, bool orb_learned_tests) {
  if (given != kAutoVocab) return given;
  return packagePath(orb_learned_tests ? kPhotoModelDir : kShippedModelDir);
}

std::string relocVocabFor(const std::string& given, bool orb_learned_tests) {
  if (given != kAutoVocab) return given;
  return packagePath(orb_learned_tests ? kPhotoRelocVocab : kRelocVocab);
}

}  // namespace binloop
