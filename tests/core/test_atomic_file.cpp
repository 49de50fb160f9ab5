#include "core/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/error.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("hf_atomic_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  size_t files_in_dir() const { return size_t(std::distance(fs::directory_iterator(dir_), fs::directory_iterator())); }
  fs::path dir_;
};

TEST_F(AtomicFile, WritesContent) {
  const fs::path p = dir_ / "out.txt";
  write_file_atomically(p.string(), [](std::ostream& o) { o << "hello\n"; });
  EXPECT_EQ(read(p), "hello\n");
  write_file_atomically(p.string(), [](std::ostream& o) { o << "replaced"; });
  EXPECT_EQ(read(p), "replaced");
  EXPECT_EQ(files_in_dir(), 1u);
}

TEST_F(AtomicFile, ThrowingWriterLeavesExistingFileUntouchedAndNoTemporary) {
  const fs::path p = dir_ / "out.txt";
  write_file_atomically(p.string(), [](std::ostream& o) { o << "original"; });
  EXPECT_THROW(write_file_atomically(p.string(),
                                     [](std::ostream& o) {
                                       o << std::string(1 << 16, 'x');  // partial output already flushed
                                       o.flush();
                                       throw std::runtime_error("writer failed");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read(p), "original");
  EXPECT_EQ(files_in_dir(), 1u) << "the temporary must be removed";
}

TEST_F(AtomicFile, ThrowingWriterCreatesNoFile) {
  const fs::path p = dir_ / "new.txt";
  EXPECT_THROW(write_file_atomically(p.string(), [](std::ostream&) { throw Error("no"); }), Error);
  EXPECT_FALSE(fs::exists(p));
  EXPECT_EQ(files_in_dir(), 0u);
}

TEST_F(AtomicFile, UnwritableDirectoryNamesThePath) {
  const std::string p = (dir_ / "no_such_dir" / "out.txt").string();
  try {
    write_file_atomically(p, [](std::ostream& o) { o << "x"; });
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

TEST_F(AtomicFile, PathWriterKeepsExtensionAndRenames) {
  const fs::path p = dir_ / "image.png";
  std::string seen_tmp;
  write_path_atomically(p.string(), [&](const std::string& tmp) {
    seen_tmp = tmp;
    std::ofstream(tmp) << "png";
  });
  EXPECT_EQ(fs::path(seen_tmp).extension(), ".png");
  EXPECT_NE(seen_tmp, p.string());
  EXPECT_EQ(fs::path(seen_tmp).parent_path(), p.parent_path());
  EXPECT_EQ(read(p), "png");
  EXPECT_EQ(files_in_dir(), 1u);
}

TEST_F(AtomicFile, PathWriterFailuresLeaveTargetUntouched) {
  const fs::path p = dir_ / "cloud.ply";
  std::ofstream(p) << "old";
  EXPECT_THROW(write_path_atomically(p.string(), [](const std::string&) {}), Error);  // wrote nothing
  EXPECT_THROW(write_path_atomically(p.string(),
                                     [](const std::string& tmp) {
                                       std::ofstream(tmp) << "half";
                                       throw std::runtime_error("crash");
                                     }),
               std::runtime_error);
  EXPECT_EQ(read(p), "old");
  EXPECT_EQ(files_in_dir(), 1u);
}

}  // namespace
}  // namespace hf
