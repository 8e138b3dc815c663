#include "binloop/io/durable_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

#include "binloop/io/data_error.h"

namespace binloop {
namespace {

std::string why() { return std::strerror(errno); }

// Closes the descriptor on every path out.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
};

}  // namespace

void syncToDisk(const std::string& path) {
  Fd f{::open(path.c_str(), O_RDONLY | O_CLOEXEC)};
  if (f.fd < 0) throw dataError(path, 0, "cannot open to flush it to disk: " + why());
  if (::fsync(f.fd) != 0) throw dataError(path, 0, "flushing to disk failed: " + why());
}

void writeDurably(const std::string& path, const std::vector<std::pair<const uint8_t*, size_t>>& pieces) {
  const std::string partial = path + ".partial";
  try {
    {
      Fd f{::open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644)};
      if (f.fd < 0) throw dataError(path, 0, "cannot write it (is the folder there and writable?): " + why());
      for (const auto& [data, size] : pieces) {
        size_t done = 0;
        while (done < size) {
          const ssize_t n = ::write(f.fd, data + done, size - done);
          if (n < 0 && errno == EINTR) continue;
          if (n <= 0) throw dataError(path, 0, "writing it failed (disk full?): " + why());
          done += static_cast<size_t>(n);
        }
      }
      if (::fsync(f.fd) != 0) throw dataError(path, 0, "flushing it to disk failed: " + why());
    }
    if (std::rename(partial.c_str(), path.c_str()) != 0)
      throw dataError(path, 0, "cannot rename " + partial + " to it: " + why());
  } catch (...) {
    std::remove(partial.c_str());
    throw;
  }
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  syncToDisk(folder.empty() ? "." : folder.string());
}

}  // namespace binloop
