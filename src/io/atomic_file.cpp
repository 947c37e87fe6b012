#include "pc_ekf/io/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace pc_ekf {
namespace {

void syncDirectory(const std::string& path) {
  std::string dir = std::filesystem::path(path).parent_path().string();
  if (dir.empty()) dir = ".";
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (fd < 0) return;  // durability of the rename only; the rename itself succeeded
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void writeFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".tmp";
  const auto failed = [&](const std::string& what) {
    const std::string reason = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw AtomicWriteError(what + " (" + reason + ")");
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) failed("cannot create " + tmp);
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      failed("cannot write " + tmp);
    }
    written += static_cast<std::size_t>(n);
  }
  // On disk before the rename: a crash leaves the old file or the new one.
  if (::fsync(fd) != 0) {
    ::close(fd);
    failed("cannot sync " + tmp);
  }
  if (::close(fd) != 0) failed("cannot close " + tmp);
  if (std::rename(tmp.c_str(), path.c_str()) != 0) failed("cannot rename " + tmp + " to it");
  syncDirectory(path);
}

}  // namespace pc_ekf
