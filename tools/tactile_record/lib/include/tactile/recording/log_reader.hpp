#pragma once

// Reads a tactile log (docs/recording.md) record by record.
//
// Recovery rule: only whole zstd frames whose content checksum holds are used. When the file
// ends inside a frame (a recorder killed while writing), next() returns kTruncated after the
// last record of the last whole frame: everything before is kept, the tail is reported with its
// offset and length. A frame that fails to decode or holds a broken record is kCorrupt; the
// records before it have been returned.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "tactile/v1/log.pb.h"

struct ZSTD_DCtx_s;

namespace tactile::recording {

enum class ReadStatus : std::uint8_t {
  kRecord,     // `out` holds the next record
  kEnd,        // the file ended after a whole frame
  kTruncated,  // the file ends inside a frame: problem() says where; records before are valid
  kCorrupt,    // a frame does not decode or holds a broken record: problem() says where
};
const char* to_string(ReadStatus s);

class LogReader {
 public:
  // Opens the file and reads its header record. Throws std::runtime_error naming the file when
  // it cannot be read, is empty, is not a tactile log, or has a format this reader does not know.
  explicit LogReader(const std::filesystem::path& path);
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  const v1::LogHeader& header() const { return header_; }
  const std::filesystem::path& path() const { return path_; }

  // The next record after the header (reusing `out`'s buffers). After kEnd, kTruncated or
  // kCorrupt every further call returns the same status.
  ReadStatus next(v1::LogRecord& out);

  // What went wrong (kTruncated, kCorrupt), one line naming the file and the byte offset.
  const std::string& problem() const { return problem_; }
  std::uint64_t file_size() const { return file_size_; }
  // Bytes of the file consumed by whole frames so far (for progress).
  std::uint64_t position() const { return frame_begin_; }
  std::uint64_t records() const { return records_; }
  std::uint64_t frames() const { return frames_; }

 private:
  ReadStatus next_frame();
  ReadStatus finish(ReadStatus s, std::string problem);

  std::filesystem::path path_;
  std::FILE* file_ = nullptr;
  ZSTD_DCtx_s* dctx_ = nullptr;
  v1::LogHeader header_;
  std::vector<char> in_;  // compressed bytes read from the file
  std::size_t in_pos_ = 0;
  std::size_t in_size_ = 0;
  std::uint64_t in_offset_ = 0;  // file offset of in_[0]
  bool eof_ = false;
  std::string frame_;              // decompressed content of the current frame
  std::size_t frame_pos_ = 0;      // next record in frame_
  std::uint64_t frame_begin_ = 0;  // file offset where the next frame starts
  std::uint64_t file_size_ = 0;
  std::uint64_t records_ = 0;
  std::uint64_t frames_ = 0;
  bool done_ = false;
  ReadStatus final_ = ReadStatus::kEnd;
  std::string problem_;
};

}  // namespace tactile::recording
