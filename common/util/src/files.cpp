#include "tactile/util/files.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace tactile::util {

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": cannot open: " + std::strerror(errno));
  std::ostringstream s;
  s << in.rdbuf();
  if (in.bad()) throw std::runtime_error(path.string() + ": read failed");
  return s.str();
}

void write_file_atomic(const std::filesystem::path& path, std::string_view content) {
  const auto parent = path.parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
    if (ec)
      throw std::runtime_error(parent.string() + ": cannot create directory: " + ec.message());
  }
  std::string tmp = path.string() + ".tmp.XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0)
    throw std::runtime_error(path.string() +
                             ": cannot create a temporary file: " + std::strerror(errno));
  const char* p = content.data();
  std::size_t left = content.size();
  while (left > 0) {
    const ssize_t n = ::write(fd, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string why = std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      throw std::runtime_error(path.string() + ": write failed: " + why);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
  // mkstemp makes the file 0600; data files are readable by others as usual.
  ::fchmod(fd, 0644);
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error(path.string() + ": flush failed: " + why);
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp.c_str());
    throw std::runtime_error(path.string() + ": rename failed: " + why);
  }
}

void check_writable_dir(const std::filesystem::path& dir) {
  const std::filesystem::path d = dir.empty() ? std::filesystem::path(".") : dir;
  std::error_code ec;
  std::filesystem::create_directories(d, ec);
  if (ec) throw std::runtime_error(d.string() + ": cannot create directory: " + ec.message());
  std::string probe = (d / ".write-probe.XXXXXX").string();
  const int fd = ::mkstemp(probe.data());
  if (fd < 0) throw std::runtime_error(d.string() + ": cannot write here: " + std::strerror(errno));
  ::close(fd);
  ::unlink(probe.c_str());
}

ReadyFile::ReadyFile(std::filesystem::path path) : path_(std::move(path)) {
  if (path_.empty()) return;
  std::error_code ec;
  std::filesystem::remove(path_, ec);
  if (ec)
    throw std::runtime_error(path_.string() +
                             ": cannot remove a stale ready file: " + ec.message());
  check_writable_dir(path_.parent_path());
}

ReadyFile::~ReadyFile() {
  if (path_.empty() || !ready_) return;
  std::error_code ec;
  std::filesystem::remove(path_, ec);
}

void ReadyFile::mark_ready() {
  if (path_.empty() || ready_) return;
  write_file_atomic(path_, "ready\n");
  ready_ = true;
}

}  // namespace tactile::util
