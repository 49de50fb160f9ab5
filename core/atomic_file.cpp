#include "core/atomic_file.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <sys/file.h>  // flock
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <random>
#include <streambuf>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/bounded_read.h"
#include "core/error.h"
#include "core/output_transaction.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

std::string errno_text(int err) { return std::strerror(err); }

fs::path parent_of(const std::string& path) {
  const fs::path parent = fs::path(path).parent_path();
  return parent.empty() ? fs::path(".") : parent;
}

// 64 bits from the kernel's generator: a temporary's name cannot be guessed, so it cannot be planted in advance.
std::string random_hex() {
  std::uint64_t bits = 0;
  if (::getrandom(&bits, sizeof bits, 0) != ssize_t(sizeof bits)) bits = (std::uint64_t(std::random_device{}()) << 32) ^ std::random_device{}();
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(bits));
  return text;
}

// A file descriptor that is closed (and, until released, its path unlinked) on every exit path.
class TempFile {
 public:
  explicit TempFile(const std::string& target) {
    const fs::path dir = parent_of(target);
    const std::string name = fs::path(target).filename().string();
    for (int attempt = 0; attempt < 16; ++attempt) {
      path_ = (dir / ("." + name + "." + random_hex() + ".tmp")).string();
      fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
      if (fd_ >= 0) return;
      if (errno != EEXIST) break;
    }
    const int err = errno;
    path_.clear();
    throw Error(target + ": cannot create a file in " + dir.string() + " (" + errno_text(err) + ")");
  }
  ~TempFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!path_.empty()) ::unlink(path_.c_str());
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  int fd() const { return fd_; }
  const std::string& path() const { return path_; }
  // fsync, close and rename over `target`; afterwards the destructor has nothing left to undo.
  void commit(const std::string& target) {
    if (::fsync(fd_) != 0) throw Error(target + ": cannot flush to disk (" + errno_text(errno) + ")");
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) throw Error(target + ": write failed (" + errno_text(errno) + ")");
    if (::rename(path_.c_str(), target.c_str()) != 0)
      throw Error(target + ": cannot move the finished file into place (" + errno_text(errno) + ")");
    path_.clear();
  }

 private:
  std::string path_;
  int fd_ = -1;
};

// An ostream buffer over a raw descriptor: write() loops over short writes and EINTR; an error fails the stream.
class FdBuffer : public std::streambuf {
 public:
  explicit FdBuffer(int fd) : fd_(fd), buffer_(1 << 16) { setp(buffer_.data(), buffer_.data() + buffer_.size()); }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    while (p < pptr()) {
      const ssize_t n = ::write(fd_, p, size_t(pptr() - p));
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        error_ = n < 0 ? errno : ENOSPC;
        return false;
      }
      p += n;
    }
    setp(buffer_.data(), buffer_.data() + buffer_.size());
    return true;
  }
  int fd_;
  int error_ = 0;
  std::vector<char> buffer_;
};

// A rename is durable only once its folder is synced; file systems that cannot sync a folder still did the rename.
void sync_folder(const fs::path& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::fsync(fd);
  ::close(fd);
}

void refuse_folder_target(const std::string& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    throw Error(path + ": is a folder, cannot write a file there");
}

}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write, bool binary) {
  (void)binary;  // POSIX streams do not translate line ends: text and binary write the same bytes
  refuse_folder_target(path);
  TempFile tmp(path);
  {
    FdBuffer buffer(tmp.fd());
    std::ostream out(&buffer);
    write(out);
    out.flush();
    if (!out) {
      const int err = buffer.error() ? buffer.error() : EIO;
      throw Error(path + ": write failed (" + errno_text(err) + ")");
    }
  }
  tmp.commit(path);
  sync_folder(parent_of(path));
}

std::string make_private_folder_beside(const std::string& target) {
  std::string pattern = (parent_of(target) / ("." + fs::path(target).filename().string() + ".XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr)
    throw Error(target + ": cannot create a folder in " + parent_of(target).string() + " (" + errno_text(errno) + ")");
  return pattern;
}

void write_path_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  refuse_folder_target(path);
  const std::string folder = make_private_folder_beside(path);
  const std::string tmp = (fs::path(folder) / fs::path(path).filename()).string();
  struct Cleanup {
    const std::string& folder;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(folder, ec);  // does not follow links
    }
  } cleanup{folder};
  write(tmp);
  struct stat st {};
  if (::lstat(tmp.c_str(), &st) != 0) throw Error(path + ": writer produced no file");
  if (!S_ISREG(st.st_mode)) throw Error(path + ": writer produced something other than a regular file");
  const int fd = ::open(tmp.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    const int err = errno;
    if (fd >= 0) ::close(fd);
    throw Error(path + ": cannot flush to disk (" + errno_text(err) + ")");
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) != 0)
    throw Error(path + ": cannot move the finished file into place (" + errno_text(errno) + ")");
  sync_folder(parent_of(path));
}

void prepare_output_folder(const std::string& dir) {
  if (dir.empty()) throw Error("expected a non-empty output folder");
  std::error_code ec;
  const fs::file_status st = fs::status(dir, ec);
  if (fs::exists(st) && !fs::is_directory(st)) throw Error(dir + ": output folder exists and is not a folder");
  if (!fs::exists(st)) {
    if (fs::is_symlink(fs::symlink_status(dir, ec))) throw Error(dir + ": output folder is a dangling link");
    fs::create_directories(dir, ec);
    if (ec) throw Error(dir + ": cannot create the output folder (" + ec.message() + ")");
  }
  try {
    TempFile probe((fs::path(dir) / "probe").string());
    const char byte = 0;
    if (::write(probe.fd(), &byte, 1) != 1) throw Error(dir + ": cannot write into the output folder (" + errno_text(errno) + ")");
  } catch (const Error& e) {
    throw Error(dir + ": output folder is not writable (" + std::string(e.what()) + ")");
  }
}

void swap_folder_into_place(const std::string& fresh, const std::string& dir) {
  std::error_code ec;
  auto fail = [&](const std::string& why) {
    fs::remove_all(fresh, ec);
    throw Error(dir + ": " + why);
  };
  const mode_t mask = ::umask(0);  // the usual permissions, not mkdtemp's 0700
  ::umask(mask);
  ::chmod(fresh.c_str(), 0777 & ~mask);
  const bool exists = fs::exists(fs::symlink_status(dir, ec));
  if (!exists) {
    if (::rename(fresh.c_str(), dir.c_str()) != 0)
      fail("cannot move the finished folder into place (" + errno_text(errno) + ")");
    sync_folder(parent_of(dir));
    return;
  }
  if (::renameat2(AT_FDCWD, fresh.c_str(), AT_FDCWD, dir.c_str(), RENAME_EXCHANGE) != 0) {
    if (errno != EINVAL && errno != ENOSYS)
      fail("cannot exchange the finished folder with the old one (" + errno_text(errno) + ")");
    // No atomic exchange here: move the old folder aside under a private name, then the new one in.
    const std::string aside = make_private_folder_beside(dir);
    if (::rename(dir.c_str(), aside.c_str()) != 0) {
      const int err = errno;
      fs::remove(aside, ec);
      fail("cannot move the old folder aside (" + errno_text(err) + ")");
    }
    if (::rename(fresh.c_str(), dir.c_str()) != 0) {
      const int err = errno;
      (void)::rename(aside.c_str(), dir.c_str());
      fail("cannot move the finished folder into place (" + errno_text(err) + ")");
    }
    fs::remove_all(aside, ec);
  } else {
    fs::remove_all(fresh, ec);  // now the old contents
  }
  sync_folder(parent_of(dir));
}

// --- OutputTransaction ------------------------------------------------------------------------------------------

namespace {

// `out` as an absolute path without a trailing "/" or "."; a link to a folder is followed (exchanging the link
// itself would leave its target stale).
fs::path output_transaction_target(const std::string& out) {
  if (out.empty()) throw Error("expected a non-empty output folder");
  fs::path p = fs::absolute(out).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();
  std::error_code ec;
  if (fs::is_symlink(fs::symlink_status(p, ec))) {
    const fs::path target = fs::canonical(p, ec);
    if (ec) throw Error(out + ": output folder is a dangling link");
    p = target;
  }
  if (p == p.root_path() || !p.has_filename()) throw Error(out + ": cannot replace the root folder with outputs");
  const fs::file_status st = fs::status(p, ec);
  if (fs::exists(st) && !fs::is_directory(st)) throw Error(out + ": output folder exists and is not a folder");
  const fs::path cwd = fs::current_path(ec);
  if (!ec) {
    if (std::mismatch(p.begin(), p.end(), cwd.begin(), cwd.end()).first == p.end())
      throw Error(out + ": output folder is (or holds) the current folder; the outputs replace the whole folder, so "
                        "give them a folder of their own");
  }
  return p;
}

// The pid written in a lock file, for the message; "unknown" when it cannot be read.
std::string output_transaction_holder(int fd) {
  char text[32] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  std::string pid = n > 0 ? std::string(text, size_t(n)) : std::string();
  while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
  return pid.empty() || pid.find_first_not_of("0123456789") != std::string::npos ? "unknown" : pid;
}

// Recreates `from` (a folder: mkdir and recurse; anything else: a hard link to the same inode, links not followed)
// at `to`. Throws hf::Error naming `out`.
void output_transaction_carry(const fs::path& from, const fs::path& to, const std::string& out) {
  struct stat st {};
  if (::lstat(from.c_str(), &st) != 0) return;  // gone meanwhile: nothing to keep
  auto fail = [&](int err) {
    throw Error(out + ": cannot carry " + from.filename().string() + " over into the new outputs (" +
                errno_text(err) + "); nothing was replaced");
  };
  if (S_ISDIR(st.st_mode)) {
    if (::mkdir(to.c_str(), st.st_mode & 07777) != 0) fail(errno);
    std::error_code ec;
    for (const fs::directory_entry& e : fs::directory_iterator(from, ec))
      output_transaction_carry(e.path(), to / e.path().filename(), out);
    if (ec) fail(ec.value());
    return;
  }
  if (::linkat(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), 0) != 0) fail(errno);
}

}  // namespace

OutputTransaction::OutputTransaction(const std::string& out) {
  const fs::path target = output_transaction_target(out);
  out_ = target.string();
  const fs::path parent = target.parent_path();
  const std::string name = target.filename().string();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) throw Error(out + ": cannot create the folder " + parent.string() + " (" + ec.message() + ")");

  const std::string lock_path = (parent / ("." + name + ".lock")).string();
  lock_fd_ = ::open(lock_path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) throw Error(out + ": cannot create the lock file " + lock_path + " (" + errno_text(errno) + ")");
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    const std::string holder = output_transaction_holder(lock_fd_);
    ::close(lock_fd_);
    lock_fd_ = -1;
    if (err == EWOULDBLOCK)
      throw Error(out + ": in use by another run (pid " + holder + "; lock " + lock_path + ")");
    throw Error(out + ": cannot lock " + lock_path + " (" + errno_text(err) + ")");
  }
  // The pid only serves the message of a second run: a failure to write it leaves the lock holding.
  const std::string pid = std::to_string(::getpid()) + "\n";
  if (::ftruncate(lock_fd_, 0) == 0) (void)!::pwrite(lock_fd_, pid.data(), pid.size(), 0);

  // Under the lock, a private folder of ours for this `out` belongs to a run that died before its commit.
  const std::string prefix = "." + name + ".run-";
  for (const fs::directory_entry& e : fs::directory_iterator(parent, ec)) {
    const std::string entry = e.path().filename().string();
    if (entry.size() == prefix.size() + 6 && entry.compare(0, prefix.size(), prefix) == 0 &&
        e.is_directory(ec) && !e.is_symlink(ec))
      fs::remove_all(e.path(), ec);  // does not follow links
  }

  std::string pattern = (parent / (prefix + "XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    const int err = errno;
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw Error(out + ": output folder is not writable: cannot create a folder in " + parent.string() + " (" +
                errno_text(err) + ")");
  }
  folder_ = pattern;
}

OutputTransaction::~OutputTransaction() {
  std::error_code ec;
  if (!committed_ && !folder_.empty()) fs::remove_all(folder_, ec);
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

void OutputTransaction::commit(const std::function<bool(const std::string&)>& previous_run_wrote) {
  std::error_code ec;
  struct stat st {};
  if (::lstat(out_.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    for (const fs::directory_entry& e : fs::directory_iterator(out_, ec)) {
      const std::string entry = e.path().filename().string();
      struct stat mine {};
      if (::lstat((fs::path(folder_) / entry).c_str(), &mine) == 0) continue;  // this run wrote it anew
      if (previous_run_wrote(entry)) continue;                                // the previous run's: replaced
      output_transaction_carry(e.path(), fs::path(folder_) / entry, out_);
    }
    if (ec) throw Error(out_ + ": cannot list the old outputs (" + ec.message() + "); nothing was replaced");
  }
  swap_folder_into_place(folder_, out_);
  committed_ = true;
}

bool read_previous_manifest(const std::string& path, nlohmann::json* json) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return false;
  try {
    *json = nlohmann::json::parse(read_regular_file(path, "previous manifest"));
    return true;
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace hf
