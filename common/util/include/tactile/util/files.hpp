#pragma once

#include <filesystem>
#include <string>
#include <string_view>

namespace tactile::util {

// Reads a whole file; throws std::runtime_error naming the file on failure.
std::string read_file(const std::filesystem::path& path);

// Writes a whole file atomically: a temporary file beside it, flushed to disk, then renamed over
// the target, so a reader sees the old file or the new one, never half of one. Creates missing
// parent directories. Throws std::runtime_error naming the file on failure.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

// A file written in pieces that appears whole or not at all: the pieces go to a temporary file
// beside `path` (missing parent directories are created); commit() flushes it to disk and renames
// it over `path`. Destroyed without commit() (an error, a stop), it removes the temporary file and
// leaves `path` as it was. A `path` that is a device, FIFO or socket (/dev/null, /dev/stdout) is
// written in place instead. Every failure throws std::runtime_error naming `path`.
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;

  void write(std::string_view bytes);
  void commit();
  const std::filesystem::path& path() const { return path_; }

 private:
  void fail(const std::string& what);

  std::filesystem::path path_;
  std::string tmp_;
  int fd_ = -1;
  bool in_place_ = false;  // `path` is a device, FIFO or socket: written as it is, not replaced
};

// Makes sure files can be written into `dir` later: creates it when missing and creates and
// removes a probe file in it. For a program that writes its results only at the end of a long
// run, so that a folder it cannot write is an error at start-up, not a result lost at the end.
// Throws std::runtime_error naming the folder and the reason.
void check_writable_dir(const std::filesystem::path& dir);

// A file that exists exactly while a program is ready to serve, for a supervisor's health check
// (docker/compose.yaml): made empty of meaning at construction (a file left by an earlier run is
// removed), written by mark_ready(), removed again by the destructor. An empty path does nothing.
class ReadyFile {
 public:
  explicit ReadyFile(std::filesystem::path path);
  ~ReadyFile();
  ReadyFile(const ReadyFile&) = delete;
  ReadyFile& operator=(const ReadyFile&) = delete;
  // Writes the file once; later calls do nothing. Throws std::runtime_error naming the file.
  void mark_ready();
  bool ready() const { return ready_; }

 private:
  std::filesystem::path path_;
  bool ready_ = false;
};

}  // namespace tactile::util
