#pragma once

// Writes a tactile log (docs/recording.md): length-delimited LogRecords in whole zstd frames.
//
// Records are buffered and compressed as one zstd frame (with its content checksum) when the
// buffer reaches frame_bytes or the oldest buffered record is flush_interval old; the frame is
// then written with one write(2) loop. A crash therefore loses at most the records not yet in a
// written frame, and a frame cut short by the crash is detected by the reader (LogReader) and
// reported as a truncated tail.
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tactile/v1/log.pb.h"

struct ZSTD_CCtx_s;

namespace tactile::recording {

inline constexpr const char* kLogFormat = "tactile-log/1";

struct LogWriterOptions {
  int level = 3;                      // zstd compression level (1 fast .. 19 small)
  std::size_t frame_bytes = 1 << 20;  // close a zstd frame once this much is buffered
  std::chrono::nanoseconds flush_interval = std::chrono::seconds(1);  // or once this old
  bool sync = false;                                                  // fdatasync after every frame
  bool overwrite = false;  // replace an existing file instead of refusing it

  // Throws std::invalid_argument naming the option and its value.
  void validate() const;
};

enum class WriteStatus : std::uint8_t { kOk, kIoError };

class LogWriter {
 public:
  // Creates `path` (refusing an existing file unless options.overwrite; creating missing
  // parent folders) and writes the header record as the file's first zstd frame at once.
  // Throws std::runtime_error naming the file, std::invalid_argument for bad options.
  LogWriter(const std::filesystem::path& path, v1::LogHeader header, LogWriterOptions options);
  ~LogWriter();  // closes (errors are then only in error())
  LogWriter(const LogWriter&) = delete;
  LogWriter& operator=(const LogWriter&) = delete;

  // Buffers one record. No allocation once the buffers have grown to the largest record and
  // frame; never throws. kIoError (with error()) when a frame had to be written and could not.
  WriteStatus append(std::int64_t receive_time_ns, std::string_view topic, std::string_view source,
                     v1::PayloadKind kind, std::span<const std::uint8_t> payload) noexcept;
  // Writes the buffered records as a frame when the oldest is flush_interval old.
  WriteStatus poll() noexcept;
  // Writes the buffered records as a frame now.
  WriteStatus flush() noexcept;
  // Flushes and closes the file (idempotent).
  WriteStatus close() noexcept;

  const std::string& error() const { return error_; }
  const std::filesystem::path& path() const { return path_; }
  std::uint64_t records() const { return records_; }
  std::uint64_t frames() const { return frames_; }
  std::uint64_t bytes_in() const { return bytes_in_; }    // record bytes (uncompressed)
  std::uint64_t bytes_out() const { return bytes_out_; }  // file size so far
  std::size_t buffered_bytes() const { return buffer_.size(); }

 private:
  WriteStatus add(const v1::LogRecord& record) noexcept;
  WriteStatus write_all(const char* data, std::size_t size) noexcept;
  WriteStatus fail(std::string what) noexcept;

  std::filesystem::path path_;
  LogWriterOptions options_;
  int fd_ = -1;
  ZSTD_CCtx_s* cctx_ = nullptr;
  v1::LogRecord record_;
  std::string buffer_;            // records of the open frame
  std::vector<char> compressed_;  // the frame being written
  std::int64_t opened_ns_ = 0;    // monotonic time of the open frame's first record
  std::string error_;
  std::uint64_t records_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t bytes_in_ = 0;
  std::uint64_t bytes_out_ = 0;
  bool failed_ = false;
};

}  // namespace tactile::recording
