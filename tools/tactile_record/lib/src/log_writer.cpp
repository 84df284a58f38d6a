#include "tactile/recording/log_writer.hpp"

#include <fcntl.h>
#include <unistd.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "tactile/util/clock.hpp"

namespace tactile::recording {
namespace {

// Appends `value` as a base-128 varint (the length prefix of a record).
void put_varint(std::string& out, std::uint64_t value) {
  while (value >= 0x80) {
    out.push_back(static_cast<char>((value & 0x7F) | 0x80));
    value >>= 7;
  }
  out.push_back(static_cast<char>(value));
}

}  // namespace

void LogWriterOptions::validate() const {
  if (level < 1 || level > ZSTD_maxCLevel()) {
    throw std::invalid_argument("zstd level must be 1.." + std::to_string(ZSTD_maxCLevel()) +
                                ", is " + std::to_string(level));
  }
  if (frame_bytes < 1024 || frame_bytes > (std::size_t{256} << 20)) {
    throw std::invalid_argument("frame size must be 1 KiB .. 256 MiB, is " +
                                std::to_string(frame_bytes) + " bytes");
  }
  if (flush_interval.count() <= 0) throw std::invalid_argument("flush interval must be positive");
}

LogWriter::LogWriter(const std::filesystem::path& path, v1::LogHeader header,
                     LogWriterOptions options)
    : path_(path), options_(options) {
  options_.validate();
  if (path.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    if (ec) throw std::runtime_error(path.string() + ": cannot create its folder: " + ec.message());
  }
  const int flags = O_WRONLY | O_CREAT | O_CLOEXEC | (options_.overwrite ? O_TRUNC : O_EXCL);
  fd_ = ::open(path.c_str(), flags, 0644);
  if (fd_ < 0) {
    const int err = errno;
    if (err == EEXIST) {
      throw std::runtime_error(path.string() +
                               ": exists already (give another name, or --overwrite)");
    }
    throw std::runtime_error(path.string() + ": cannot create: " + std::strerror(err));
  }
  cctx_ = ZSTD_createCCtx();
  if (cctx_ == nullptr) throw std::runtime_error("zstd: cannot create a compression context");
  ZSTD_CCtx_setParameter(cctx_, ZSTD_c_compressionLevel, options_.level);
  ZSTD_CCtx_setParameter(cctx_, ZSTD_c_checksumFlag, 1);
  ZSTD_CCtx_setParameter(cctx_, ZSTD_c_contentSizeFlag, 1);
  buffer_.reserve(options_.frame_bytes + (64 << 10));
  compressed_.resize(ZSTD_compressBound(buffer_.capacity()));

  header.set_format(kLogFormat);
  v1::LogRecord first;
  *first.mutable_header() = std::move(header);
  if (add(first) != WriteStatus::kOk || flush() != WriteStatus::kOk) {
    const std::string why = error_;
    close();
    throw std::runtime_error(why);
  }
  records_ = 0;  // the header is not counted
}

LogWriter::~LogWriter() {
  close();
  ZSTD_freeCCtx(cctx_);
}

WriteStatus LogWriter::fail(std::string what) noexcept {
  failed_ = true;
  try {
    error_ = path_.string() + ": " + std::move(what);
  } catch (...) {
  }
  return WriteStatus::kIoError;
}

WriteStatus LogWriter::add(const v1::LogRecord& record) noexcept {
  if (failed_ || fd_ < 0) return WriteStatus::kIoError;
  try {
    const std::size_t size = record.ByteSizeLong();
    if (buffer_.empty()) opened_ns_ = util::monotonic_ns();
    put_varint(buffer_, size);
    const std::size_t at = buffer_.size();
    buffer_.resize(at + size);
    record.SerializeWithCachedSizesToArray(reinterpret_cast<std::uint8_t*>(buffer_.data() + at));
    bytes_in_ += size;
    ++records_;
  } catch (const std::exception& e) {
    return fail(std::string("cannot buffer a record: ") + e.what());
  }
  if (buffer_.size() >= options_.frame_bytes) return flush();
  return WriteStatus::kOk;
}

WriteStatus LogWriter::append(std::int64_t receive_time_ns, std::string_view topic,
                              std::string_view source, v1::PayloadKind kind,
                              std::span<const std::uint8_t> payload) noexcept {
  try {
    record_.set_receive_time_ns(receive_time_ns);
    record_.mutable_topic()->assign(topic.data(), topic.size());
    record_.mutable_source()->assign(source.data(), source.size());
    record_.set_kind(kind);
    record_.mutable_payload()->assign(reinterpret_cast<const char*>(payload.data()),
                                      payload.size());
  } catch (const std::exception& e) {
    return fail(std::string("cannot buffer a record: ") + e.what());
  }
  return add(record_);
}

WriteStatus LogWriter::poll() noexcept {
  if (buffer_.empty() || failed_) return failed_ ? WriteStatus::kIoError : WriteStatus::kOk;
  if (util::monotonic_ns() - opened_ns_ >= options_.flush_interval.count()) return flush();
  return WriteStatus::kOk;
}

WriteStatus LogWriter::write_all(const char* data, std::size_t size) noexcept {
  while (size > 0) {
    const ssize_t n = ::write(fd_, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      return fail(std::string("write failed: ") + std::strerror(errno));
    }
    data += n;
    size -= static_cast<std::size_t>(n);
    bytes_out_ += static_cast<std::uint64_t>(n);
  }
  return WriteStatus::kOk;
}

WriteStatus LogWriter::flush() noexcept {
  if (failed_ || fd_ < 0) return WriteStatus::kIoError;
  if (buffer_.empty()) return WriteStatus::kOk;
  try {
    const std::size_t bound = ZSTD_compressBound(buffer_.size());
    if (compressed_.size() < bound) compressed_.resize(bound);
  } catch (const std::exception& e) {
    return fail(std::string("cannot compress: ") + e.what());
  }
  const std::size_t n =
      ZSTD_compress2(cctx_, compressed_.data(), compressed_.size(), buffer_.data(), buffer_.size());
  if (ZSTD_isError(n) != 0) return fail(std::string("zstd: ") + ZSTD_getErrorName(n));
  if (write_all(compressed_.data(), n) != WriteStatus::kOk) return WriteStatus::kIoError;
  if (options_.sync && ::fdatasync(fd_) != 0) {
    return fail(std::string("fdatasync failed: ") + std::strerror(errno));
  }
  buffer_.clear();
  ++frames_;
  return WriteStatus::kOk;
}

WriteStatus LogWriter::close() noexcept {
  if (fd_ < 0) return failed_ ? WriteStatus::kIoError : WriteStatus::kOk;
  WriteStatus s = failed_ ? WriteStatus::kIoError : flush();
  if (::close(fd_) != 0 && s == WriteStatus::kOk) {
    s = fail(std::string("close failed: ") + std::strerror(errno));
  }
  fd_ = -1;
  return s;
}

}  // namespace tactile::recording
