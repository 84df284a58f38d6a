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
  AtomicFileWriter file(path);
  file.write(content);
  file.commit();
}

AtomicFileWriter::AtomicFileWriter(std::filesystem::path path) : path_(std::move(path)) {
  // A device, FIFO or socket is written in place: a temporary file renamed over it would replace
  // it (as root, `--report /dev/null` once made /dev/null a regular file for every program).
  struct stat st {};
  if (::stat(path_.c_str(), &st) == 0 && !S_ISREG(st.st_mode) && !S_ISDIR(st.st_mode)) {
    fd_ = ::open(path_.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0)
      throw std::runtime_error(path_.string() +
                               ": cannot open for writing: " + std::strerror(errno));
    in_place_ = true;
    return;
  }
  const auto parent = path_.parent_path();
  if (!parent.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(parent, ec);
    if (ec)
      throw std::runtime_error(parent.string() + ": cannot create directory: " + ec.message());
  }
  tmp_ = path_.string() + ".tmp.XXXXXX";
  fd_ = ::mkstemp(tmp_.data());
  if (fd_ < 0)
    throw std::runtime_error(path_.string() +
                             ": cannot create a temporary file: " + std::strerror(errno));
  // mkstemp makes the file 0600; data files are readable by others as usual.
  ::fchmod(fd_, 0644);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (fd_ >= 0) {
    ::close(fd_);
    if (!in_place_) ::unlink(tmp_.c_str());
  }
}

void AtomicFileWriter::fail(const std::string& what) {
  const std::string why = std::strerror(errno);
  ::close(fd_);
  if (!in_place_) ::unlink(tmp_.c_str());
  fd_ = -1;
  throw std::runtime_error(path_.string() + ": " + what + ": " + why);
}

void AtomicFileWriter::write(std::string_view bytes) {
  if (fd_ < 0) throw std::runtime_error(path_.string() + ": write after the file was closed");
  const char* p = bytes.data();
  std::size_t left = bytes.size();
  while (left > 0) {
    const ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write failed");
    }
    p += n;
    left -= static_cast<std::size_t>(n);
  }
}

void AtomicFileWriter::commit() {
  if (fd_ < 0) throw std::runtime_error(path_.string() + ": commit after the file was closed");
  if (in_place_) {
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0)
      throw std::runtime_error(path_.string() + ": flush failed: " + std::strerror(errno));
    return;
  }
  if (::fsync(fd_) != 0) fail("flush failed");
  if (::close(fd_) != 0) {
    fd_ = -1;
    const std::string why = std::strerror(errno);
    ::unlink(tmp_.c_str());
    throw std::runtime_error(path_.string() + ": flush failed: " + why);
  }
  fd_ = -1;
  if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
    const std::string why = std::strerror(errno);
    ::unlink(tmp_.c_str());
    throw std::runtime_error(path_.string() + ": rename failed: " + why);
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
