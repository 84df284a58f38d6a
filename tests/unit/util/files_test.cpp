#include "tactile/util/files.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <thread>

#include "process.hpp"

namespace {

namespace fs = std::filesystem;
using tactile::util::check_writable_dir;

class WritableDir : public ::testing::Test {
 protected:
  // The read-only case takes the write bit away: give it back so the folder can be removed.
  void TearDown() override { ::chmod(dir_.c_str(), 0755); }
  tactile::testing::TempDir tmp_;
  const fs::path& dir_ = tmp_.path();
};

TEST_F(WritableDir, CreatesAMissingFolderAndLeavesNoProbeBehind) {
  const fs::path out = dir_ / "a" / "b";
  check_writable_dir(out);
  EXPECT_TRUE(fs::is_directory(out));
  EXPECT_TRUE(fs::is_empty(out));
}

TEST_F(WritableDir, RefusesAFolderItCannotWriteNamingIt) {
  if (::geteuid() == 0) {
    // Root writes through permission bits: a path under a regular file is refused instead.
    const fs::path file = dir_ / "plain";
    {
      std::FILE* f = std::fopen(file.c_str(), "w");
      ASSERT_NE(f, nullptr);
      std::fclose(f);
    }
    try {
      check_writable_dir(file / "out");
      FAIL() << "a folder under a regular file was accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find((file / "out").string()), std::string::npos) << e.what();
    }
    return;
  }
  ASSERT_EQ(::chmod(dir_.c_str(), 0555), 0);
  try {
    check_writable_dir(dir_);
    FAIL() << "a read-only folder was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(dir_.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot write"), std::string::npos) << e.what();
  }
}

}  // namespace

namespace {

using tactile::util::ReadyFile;

TEST_F(WritableDir, ReadyFileExistsExactlyWhileReady) {
  const fs::path path = dir_ / "ready";
  {
    std::FILE* f = std::fopen(path.c_str(), "w");  // left behind by an earlier run
    ASSERT_NE(f, nullptr);
    std::fclose(f);
  }
  {
    ReadyFile ready(path);
    EXPECT_FALSE(fs::exists(path)) << "a stale ready file survived the start";
    EXPECT_FALSE(ready.ready());
    ready.mark_ready();
    EXPECT_TRUE(fs::exists(path));
    EXPECT_TRUE(ready.ready());
    ready.mark_ready();  // once is enough; again is harmless
    EXPECT_TRUE(fs::exists(path));
  }
  EXPECT_FALSE(fs::exists(path)) << "the ready file outlived the program";
}

TEST(ReadyFileNone, AnEmptyPathDoesNothing) {
  ReadyFile ready{fs::path()};
  ready.mark_ready();
  EXPECT_FALSE(ready.ready());
}

// A FIFO (as /dev/null, a device) is written in place: renamed over, it became a regular file,
// and as root `--report /dev/null` once did that to /dev/null (issue 39's notes). The reader on
// the other end gets the bytes and the FIFO is still a FIFO; a regular file is still replaced
// whole.
TEST(AtomicFileWriter, WritesADeviceOrFifoInPlaceNotReplacingIt) {
  tactile::testing::TempDir tmp;
  const fs::path fifo = tmp / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string got;
  std::thread reader([&] {
    std::ifstream in(fifo);
    got.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  });
  // A second name for the FIFO: were it replaced, the reader, blocked in its open, is let go
  // through this one, and the test fails instead of hanging.
  const fs::path link = tmp / "fifo-link";
  ASSERT_EQ(::link(fifo.c_str(), link.c_str()), 0);
  tactile::util::write_file_atomic(fifo, "report\n");
  struct stat st {};
  ASSERT_EQ(::stat(fifo.c_str(), &st), 0);
  const bool still_fifo = S_ISFIFO(st.st_mode);
  if (!still_fifo) std::ofstream(link) << "";
  reader.join();
  EXPECT_TRUE(still_fifo) << "the FIFO was replaced";
  EXPECT_EQ(got, "report\n");
  EXPECT_EQ(std::distance(fs::directory_iterator(tmp.path()), fs::directory_iterator()), 2)
      << "a temporary file was left";

  const fs::path file = tmp / "file";
  tactile::util::write_file_atomic(file, "old");
  const ino_t before = fs::exists(file) ? (::stat(file.c_str(), &st), st.st_ino) : 0;
  tactile::util::write_file_atomic(file, "new");
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  EXPECT_NE(st.st_ino, before) << "a regular file is replaced whole, not rewritten";
  EXPECT_TRUE(S_ISREG(st.st_mode));
}

}  // namespace
