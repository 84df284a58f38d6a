#include "tactile/util/files.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>

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

}  // namespace
