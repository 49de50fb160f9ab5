#include "core/atomic_file.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/error.h"
#include "core/output_transaction.h"

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
  EXPECT_EQ(fs::path(seen_tmp).filename(), p.filename()) << "format-by-name writers see the real name";
  EXPECT_EQ(fs::path(seen_tmp).parent_path().parent_path(), p.parent_path()) << "a private folder beside the target";
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

// Issue 14.1: "ln -s ~/victim.txt out/trajectory.tmp$$.txt" made the writer overwrite the victim. Temporaries now
// have unguessable names and are created exclusively, so links planted at any predictable name stay untouched.
TEST_F(AtomicFile, LinksPlantedAtPredictableTemporaryNamesAreNotFollowed) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "victim";
  fs::create_directories(dir_ / "out");
  const std::string pid = std::to_string(::getpid());
  for (const std::string& name : std::vector<std::string>{"trajectory.tmp" + pid + ".txt", "trajectory.txt.tmp." + pid,
                                                          "trajectory.txt.tmp", ".trajectory.txt.tmp"})
    fs::create_symlink(victim, dir_ / "out" / name);
  const fs::path target = dir_ / "out" / "trajectory.txt";
  write_file_atomically(target.string(), [](std::ostream& o) { o << "trajectory"; });
  write_path_atomically((dir_ / "out" / "trajectory.png").string(), [](const std::string& tmp) { std::ofstream(tmp) << "png"; });
  EXPECT_EQ(read(victim), "victim");
  EXPECT_FALSE(fs::is_symlink(target));
  EXPECT_EQ(read(target), "trajectory");
}

// A link at the target itself is replaced by the new file (rename does not follow it); the link's target is kept.
TEST_F(AtomicFile, LinkAtTargetIsReplacedNotWrittenThrough) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "victim";
  const fs::path target = dir_ / "report.json";
  fs::create_symlink(victim, target);
  write_file_atomically(target.string(), [](std::ostream& o) { o << "{}"; });
  EXPECT_FALSE(fs::is_symlink(target));
  EXPECT_EQ(read(target), "{}");
  EXPECT_EQ(read(victim), "victim");
}

// The temporary is a fresh regular file with a random hidden name beside the target, a different one each time.
TEST_F(AtomicFile, TemporaryIsAFreshHiddenFileWithARandomName) {
  const fs::path target = dir_ / "mesh.ply";
  std::vector<std::string> seen;
  for (int i = 0; i < 2; ++i)
    write_file_atomically(target.string(), [&](std::ostream&) {
      for (const auto& e : fs::directory_iterator(dir_))
        if (e.path() != target) {
          seen.push_back(e.path().filename().string());
          EXPECT_TRUE(fs::is_regular_file(fs::symlink_status(e.path())));
        }
    });
  ASSERT_EQ(seen.size(), 2u);
  EXPECT_NE(seen[0], seen[1]);
  for (const auto& name : seen) {
    EXPECT_EQ(name.rfind(".mesh.ply.", 0), 0u) << name;
    EXPECT_GE(name.size(), std::string(".mesh.ply.").size() + 16 + 4) << name << ": 64 random bits in hex, then .tmp";
  }
  EXPECT_EQ(files_in_dir(), 1u);
}

TEST_F(AtomicFile, FolderAtTargetIsRefusedAndKept) {
  fs::create_directories(dir_ / "out.txt" / "inner");
  EXPECT_THROW(write_file_atomically((dir_ / "out.txt").string(), [](std::ostream& o) { o << "x"; }), Error);
  EXPECT_THROW(write_path_atomically((dir_ / "out.txt").string(), [](const std::string& t) { std::ofstream(t) << "x"; }),
               Error);
  EXPECT_TRUE(fs::is_directory(dir_ / "out.txt" / "inner"));
  EXPECT_EQ(files_in_dir(), 1u);
}

// A name-based writer that leaves a link instead of a file must not get it renamed into place.
TEST_F(AtomicFile, PathWriterResultMustBeARegularFile) {
  const fs::path victim = dir_ / "victim.txt";
  std::ofstream(victim) << "victim";
  EXPECT_THROW(write_path_atomically((dir_ / "cloud.pcd").string(),
                                     [&](const std::string& tmp) { fs::create_symlink(victim, tmp); }),
               Error);
  EXPECT_FALSE(fs::exists(fs::symlink_status(dir_ / "cloud.pcd")));
  EXPECT_EQ(files_in_dir(), 1u) << "the private folder is removed";
}

// Issue 14.3: `run` found an unusable --out only after the last frame. prepare_output_folder says so up front.
TEST_F(AtomicFile, PrepareOutputFolderCreatesOrRefusesUpFront) {
  const fs::path fresh = dir_ / "a" / "b";
  prepare_output_folder(fresh.string());
  EXPECT_TRUE(fs::is_directory(fresh));
  EXPECT_EQ(size_t(std::distance(fs::directory_iterator(fresh), fs::directory_iterator())), 0u) << "no probe left";
  const fs::path file = dir_ / "afile";
  std::ofstream(file) << "x";
  EXPECT_THROW(prepare_output_folder(file.string()), Error);
  EXPECT_THROW(prepare_output_folder((file / "sub").string()), Error);
  fs::create_symlink(dir_ / "nowhere", dir_ / "dangling");
  EXPECT_THROW(prepare_output_folder((dir_ / "dangling").string()), Error);
  if (fs::is_directory("/proc/self")) {
    EXPECT_THROW(prepare_output_folder("/proc/self"), Error);
  }
  if (::geteuid() != 0) {  // root writes into read-only folders anyway
    fs::create_directories(dir_ / "ro");
    fs::permissions(dir_ / "ro", fs::perms::owner_read | fs::perms::owner_exec);
    EXPECT_THROW(prepare_output_folder((dir_ / "ro").string()), Error);
    fs::permissions(dir_ / "ro", fs::perms::owner_all);
  }
}

// Issue 14.2: generate's folder swap. The old folder's contents go, links inside it are removed, not followed.
TEST_F(AtomicFile, SwapFolderReplacesTheOldOneWithoutFollowingLinks) {
  const fs::path keep = dir_ / "keep";
  fs::create_directories(keep);
  std::ofstream(keep / "precious.txt") << "precious";
  const fs::path target = dir_ / "results";
  fs::create_directories(target / "rgb");
  std::ofstream(target / "rgb.txt") << "old";
  fs::create_symlink(keep, target / "rgb" / "link");
  for (int round = 0; round < 2; ++round) {
    const std::string fresh = make_private_folder_beside(target.string());
    EXPECT_EQ(fs::path(fresh).parent_path(), dir_);
    std::ofstream(fs::path(fresh) / "rgb.txt") << "new" << round;
    swap_folder_into_place(fresh, target.string());
    EXPECT_FALSE(fs::exists(fresh));
    EXPECT_EQ(read(target / "rgb.txt"), "new" + std::to_string(round));
    EXPECT_FALSE(fs::exists(target / "rgb"));
  }
  EXPECT_EQ(read(keep / "precious.txt"), "precious");
  EXPECT_EQ(files_in_dir(), 2u) << "keep and results, nothing left behind";
}

// Issue 35: outputs as one transaction. Files the previous run wrote are replaced or dropped, every other entry of
// the old folder (files, folders, links) is carried over; nothing changes before commit().
TEST_F(AtomicFile, TransactionCarriesOverWhatThePreviousRunDidNotWrite) {
  const fs::path out = dir_ / "out";
  fs::create_directories(out / "sub");
  std::ofstream(out / "report.json") << "old";
  std::ofstream(out / "trajectory.png") << "old plot";
  std::ofstream(out / "notes.txt") << "mine";
  std::ofstream(out / "sub" / "deep.txt") << "deep";
  fs::create_symlink("/nonexistent", out / "link");
  {
    OutputTransaction t(out.string());
    EXPECT_EQ(fs::path(t.folder()).parent_path(), dir_);
    std::ofstream(fs::path(t.folder()) / "report.json") << "new";
    EXPECT_EQ(read(out / "report.json"), "old");  // nothing visible before the commit
    t.commit([](const std::string& name) { return name == "report.json" || name == "trajectory.png"; });
  }
  EXPECT_EQ(read(out / "report.json"), "new");
  EXPECT_FALSE(fs::exists(out / "trajectory.png"));  // the previous run's, and this run did not write it
  EXPECT_EQ(read(out / "notes.txt"), "mine");
  EXPECT_EQ(read(out / "sub" / "deep.txt"), "deep");
  EXPECT_TRUE(fs::is_symlink(out / "link"));
  EXPECT_EQ(files_in_dir(), 2u) << "only out and its lock file remain";  // no private folder left
  EXPECT_TRUE(fs::exists(dir_ / ".out.lock"));
}

TEST_F(AtomicFile, TransactionWithoutCommitLeavesOutAsItWas) {
  const fs::path out = dir_ / "out";
  {
    OutputTransaction t(out.string());
    std::ofstream(fs::path(t.folder()) / "report.json") << "half";
  }
  EXPECT_FALSE(fs::exists(out)) << "an absent --out stays absent";
  fs::create_directories(out);
  std::ofstream(out / "report.json") << "old";
  { OutputTransaction t(out.string()); }
  EXPECT_EQ(read(out / "report.json"), "old");
  EXPECT_EQ(files_in_dir(), 2u);
}

TEST_F(AtomicFile, TransactionIsExclusiveAndCleansUpAfterDeadRuns) {
  const fs::path out = dir_ / "out";
  fs::create_directories(dir_ / ".out.run-abc123" / "x");  // what a run killed with SIGKILL leaves
  OutputTransaction first(out.string());
  EXPECT_FALSE(fs::exists(dir_ / ".out.run-abc123"));
  try {
    OutputTransaction second(out.string());
    ADD_FAILURE() << "a second transaction on the same folder was allowed";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("in use by another run (pid " + std::to_string(::getpid()) + "; lock "),
              std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(fs::exists(first.folder())) << "the refused second transaction removed the first one's folder";
  std::ofstream(dir_ / "afile") << "x";
  EXPECT_THROW(OutputTransaction((dir_ / "afile").string()), Error);
}

}  // namespace
}  // namespace hf
