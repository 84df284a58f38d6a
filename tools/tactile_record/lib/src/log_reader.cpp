#include "tactile/recording/log_reader.hpp"

#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "tactile/recording/log_writer.hpp"

namespace tactile::recording {
namespace {

constexpr std::size_t kReadChunk = 256 << 10;
// A frame's content may not exceed this (the writer closes frames at 256 MiB at most).
constexpr std::size_t kMaxFrameContent = std::size_t{512} << 20;
constexpr std::uint32_t kZstdMagic = 0xFD2FB528U;

// Reads a varint at frame[pos]; false when it runs past the end or beyond 64 bits.
bool get_varint(const std::string& frame, std::size_t& pos, std::uint64_t& value) {
  value = 0;
  for (int shift = 0; shift < 64; shift += 7) {
    if (pos >= frame.size()) return false;
    const auto byte = static_cast<std::uint8_t>(frame[pos++]);
    value |= static_cast<std::uint64_t>(byte & 0x7F) << shift;
    if ((byte & 0x80) == 0) return true;
  }
  return false;
}

}  // namespace

const char* to_string(ReadStatus s) {
  switch (s) {
    case ReadStatus::kRecord:
      return "record";
    case ReadStatus::kEnd:
      return "end";
    case ReadStatus::kTruncated:
      return "truncated";
    case ReadStatus::kCorrupt:
      return "corrupt";
  }
  return "?";
}

LogReader::LogReader(const std::filesystem::path& path) : path_(path) {
  const std::string name = path.string();
  file_ = std::fopen(path.c_str(), "rb");
  if (file_ == nullptr) throw std::runtime_error(name + ": cannot open: " + std::strerror(errno));
  std::error_code ec;
  file_size_ = std::filesystem::file_size(path, ec);
  if (ec) file_size_ = 0;
  dctx_ = ZSTD_createDCtx();
  if (dctx_ == nullptr) {
    std::fclose(file_);
    throw std::runtime_error("zstd: cannot create a decompression context");
  }
  in_.resize(kReadChunk);
  try {
    unsigned char magic[4] = {};
    const std::size_t got = std::fread(magic, 1, 4, file_);
    if (got == 0) {
      throw std::runtime_error(name +
                               ": empty file (the recorder stopped before writing anything)");
    }
    const std::uint32_t m =
        static_cast<std::uint32_t>(magic[0]) | (static_cast<std::uint32_t>(magic[1]) << 8) |
        (static_cast<std::uint32_t>(magic[2]) << 16) | (static_cast<std::uint32_t>(magic[3]) << 24);
    if (got < 4 || m != kZstdMagic) {
      throw std::runtime_error(name + ": not a tactile log (it does not start with a zstd frame)");
    }
    std::rewind(file_);
    v1::LogRecord first;
    const ReadStatus s = next(first);
    if (s != ReadStatus::kRecord || !first.has_header()) {
      throw std::runtime_error(
          s == ReadStatus::kRecord
              ? name + ": not a tactile log (its first record is not a header)"
              : name + ": no header: " + (problem_.empty() ? std::string("no records") : problem_));
    }
    header_ = std::move(*first.mutable_header());
    if (header_.format() != kLogFormat) {
      throw std::runtime_error(name + ": format '" + header_.format() +
                               "' is not one this reader knows (" + kLogFormat + ")");
    }
    records_ = 0;
  } catch (...) {
    ZSTD_freeDCtx(dctx_);
    std::fclose(file_);
    throw;
  }
}

LogReader::~LogReader() {
  ZSTD_freeDCtx(dctx_);
  if (file_ != nullptr) std::fclose(file_);
}

ReadStatus LogReader::finish(ReadStatus s, std::string problem) {
  done_ = true;
  final_ = s;
  problem_ = std::move(problem);
  return s;
}

ReadStatus LogReader::next_frame() {
  frame_.clear();
  frame_pos_ = 0;
  ZSTD_DCtx_reset(dctx_, ZSTD_reset_session_only);
  bool started = false;
  std::size_t produced = 0;
  for (;;) {
    if (in_pos_ == in_size_) {
      std::size_t got = 0;
      if (!eof_) {
        in_offset_ += in_size_;
        got = std::fread(in_.data(), 1, in_.size(), file_);
        in_size_ = got;
        in_pos_ = 0;
        if (got < in_.size()) {
          if (std::ferror(file_) != 0) {
            return finish(ReadStatus::kCorrupt,
                          path_.string() + ": read error at byte " + std::to_string(in_offset_));
          }
          eof_ = true;
        }
      }
      if (got == 0) {
        if (!started) return finish(ReadStatus::kEnd, {});
        const std::uint64_t tail = in_offset_ + in_size_ - frame_begin_;
        return finish(ReadStatus::kTruncated,
                      path_.string() + ": truncated tail: the last " + std::to_string(tail) +
                          " bytes (from byte " + std::to_string(frame_begin_) +
                          ") are an incomplete zstd frame; the " + std::to_string(records_) +
                          " records before it are kept");
      }
    }
    started = true;
    if (frame_.size() - produced < ZSTD_DStreamOutSize()) {
      if (frame_.size() >= kMaxFrameContent) {
        return finish(ReadStatus::kCorrupt, path_.string() + ": the zstd frame at byte " +
                                                std::to_string(frame_begin_) +
                                                " is larger than any the writer makes");
      }
      frame_.resize(frame_.size() + (std::size_t{1} << 20));
    }
    ZSTD_inBuffer in{in_.data() + in_pos_, in_size_ - in_pos_, 0};
    ZSTD_outBuffer out{frame_.data() + produced, frame_.size() - produced, 0};
    const std::size_t r = ZSTD_decompressStream(dctx_, &out, &in);
    in_pos_ += in.pos;
    produced += out.pos;
    if (ZSTD_isError(r) != 0) {
      return finish(ReadStatus::kCorrupt, path_.string() + ": the zstd frame at byte " +
                                              std::to_string(frame_begin_) +
                                              " does not decode: " + ZSTD_getErrorName(r));
    }
    if (r == 0) {
      frame_.resize(produced);
      frame_begin_ = in_offset_ + in_pos_;
      ++frames_;
      return ReadStatus::kRecord;
    }
  }
}

ReadStatus LogReader::next(v1::LogRecord& out) {
  if (done_) return final_;
  while (frame_pos_ >= frame_.size()) {
    const ReadStatus s = next_frame();
    if (s != ReadStatus::kRecord) return s;
  }
  std::uint64_t size = 0;
  const std::size_t at = frame_pos_;
  if (!get_varint(frame_, frame_pos_, size) || size > frame_.size() - frame_pos_) {
    return finish(ReadStatus::kCorrupt, path_.string() +
                                            ": broken record length inside the frame "
                                            "that ends at byte " +
                                            std::to_string(frame_begin_) + " (record offset " +
                                            std::to_string(at) + ")");
  }
  if (!out.ParseFromArray(frame_.data() + frame_pos_, static_cast<int>(size))) {
    return finish(ReadStatus::kCorrupt, path_.string() +
                                            ": a record that does not parse inside "
                                            "the frame that ends at byte " +
                                            std::to_string(frame_begin_));
  }
  frame_pos_ += size;
  ++records_;
  return ReadStatus::kRecord;
}

}  // namespace tactile::recording
