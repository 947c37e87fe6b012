// Replacing a file so that a reader (or a crash) sees the old content or the
// new one, never half: write `path.tmp`, fsync it, rename it over `path`
// (atomic on POSIX), then fsync the directory for the rename's durability.
#pragma once

#include <stdexcept>
#include <string>

namespace pc_ekf {

// What failed and the system's reason, e.g. "cannot create x.tmp (No such
// file or directory)". The temporary has been removed when this is thrown.
class AtomicWriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void writeFileAtomically(const std::string& path, const std::string& text);

}  // namespace pc_ekf
