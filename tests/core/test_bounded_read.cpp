// core/bounded_read and quote_for_message (issue 14.7, 14.8): only regular files, bounded, never blocking; input
// quoted short and printable.
#include "core/bounded_read.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

class BoundedRead : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("hf_bounded_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string error_of(const std::string& path, std::size_t limit = kMaxTextFileBytes) {
    try {
      read_regular_file(path, "list", limit);
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(BoundedRead, ReadsARegularFileAndALinkToOne) {
  std::ofstream(dir_ / "a.txt", std::ios::binary) << std::string("abc\0def", 7);
  EXPECT_EQ(read_regular_file((dir_ / "a.txt").string(), "list"), std::string("abc\0def", 7));
  fs::create_symlink(dir_ / "a.txt", dir_ / "link.txt");
  EXPECT_EQ(read_regular_file((dir_ / "link.txt").string(), "list").size(), 7u);
  std::ofstream(dir_ / "empty.txt");
  EXPECT_EQ(read_regular_file((dir_ / "empty.txt").string(), "list"), "");
}

// A FIFO would block open() and read() forever; it is refused at once (a hang here is the failure).
TEST_F(BoundedRead, FifoIsRefusedWithoutBlocking) {
  const fs::path fifo = dir_ / "rgb.txt";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const std::string e = error_of(fifo.string());
  EXPECT_NE(e.find(fifo.string()), std::string::npos) << e;
  EXPECT_NE(e.find("FIFO"), std::string::npos) << e;
}

// A link to /dev/zero would be read until memory runs out; devices and folders are refused by what they are.
TEST_F(BoundedRead, DevicesAndFoldersAreRefusedByKind) {
  if (fs::exists("/dev/zero")) {
    fs::create_symlink("/dev/zero", dir_ / "groundtruth.txt");
    const std::string e = error_of((dir_ / "groundtruth.txt").string());
    EXPECT_NE(e.find("character device"), std::string::npos) << e;
  }
  EXPECT_NE(error_of(dir_.string()).find("a folder, not a regular file"), std::string::npos);
  EXPECT_NE(error_of((dir_ / "missing").string()).find("No such file"), std::string::npos);
}

TEST_F(BoundedRead, SizeLimitIsNamed) {
  std::ofstream(dir_ / "big.txt") << std::string(3000, 'x');
  EXPECT_EQ(read_regular_file((dir_ / "big.txt").string(), "list", 3000).size(), 3000u);
  const std::string e = error_of((dir_ / "big.txt").string(), 2048);
  EXPECT_NE(e.find("larger than the 2048 bytes limit"), std::string::npos) << e;
}

// Issue 14.8: a 10 MB token with a terminal escape sequence is quoted as 40 printable characters.
TEST(QuoteForMessage, BoundedAndPrintable) {
  const std::string token = "\x1b[31mRED" + std::string(10'000'000, 'x');
  const std::string q = quote_for_message(token);
  EXPECT_EQ(q.size(), 1u + 40u + 3u + 1u);
  EXPECT_EQ(q.substr(0, 9), "'?[31mRED");
  for (char c : q) EXPECT_TRUE(c >= 32 && c < 127) << int(c);
  EXPECT_EQ(quote_for_message("ok"), "'ok'");
}

}  // namespace
}  // namespace hf
