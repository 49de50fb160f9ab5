#include "core/atomic_file.h"

#include <fcntl.h>
#include <stdio.h>  // renameat2
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <random>
#include <streambuf>
#include <vector>

#include "core/error.h"

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

}  // namespace hf
