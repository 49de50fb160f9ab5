#include "core/bounded_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <algorithm>
#include <cstring>

#include "core/error.h"
#include "core/regular_path.h"

namespace hf {
namespace {

const char* kind_of(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

std::string limit_text(std::size_t bytes) {
  if (bytes >= (std::size_t(1) << 30) && bytes % (std::size_t(1) << 30) == 0) return std::to_string(bytes >> 30) + " GiB";
  if (bytes >= (std::size_t(1) << 20) && bytes % (std::size_t(1) << 20) == 0) return std::to_string(bytes >> 20) + " MiB";
  return std::to_string(bytes) + " bytes";
}

class Fd {
 public:
  explicit Fd(int fd) : fd_(fd) {}
  ~Fd() {
    if (fd_ >= 0) ::close(fd_);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  int get() const { return fd_; }

 private:
  int fd_;
};

}  // namespace

std::string read_regular_file(const std::string& path, const std::string& what, std::size_t max_bytes) {
  const std::string cannot = path + ": cannot read " + what;
  const Fd fd(::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY));
  if (fd.get() < 0) throw Error(cannot + " (" + std::strerror(errno) + ")");
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0) throw Error(cannot + " (" + std::strerror(errno) + ")");
  if (!S_ISREG(st.st_mode)) throw Error(cannot + ": it is " + kind_of(st.st_mode) + ", not a regular file");
  if (std::size_t(st.st_size) > max_bytes)
    throw Error(path + ": " + what + " is larger than the " + limit_text(max_bytes) + " limit");
  // Regular files never block; clearing O_NONBLOCK keeps reads on network file systems ordinary.
  ::fcntl(fd.get(), F_SETFL, ::fcntl(fd.get(), F_GETFL) & ~O_NONBLOCK);
  std::string bytes(std::size_t(st.st_size), '\0');
  std::size_t got = 0;
  for (;;) {
    if (got == bytes.size()) {
      if (bytes.size() > max_bytes) break;
      bytes.resize(std::min(max_bytes + 1, bytes.size() + (std::size_t(1) << 16)));  // the file may be growing
    }
    const ssize_t n = ::read(fd.get(), bytes.data() + got, bytes.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw Error(cannot + " (" + std::strerror(errno) + ")");
    if (n == 0) break;
    got += std::size_t(n);
  }
  if (got > max_bytes) throw Error(path + ": " + what + " is larger than the " + limit_text(max_bytes) + " limit");
  bytes.resize(got);
  return bytes;
}

void require_regular_path(const std::string& path, const std::string& what, bool folder_allowed) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) throw Error(path + ": cannot read " + what + " (" + std::strerror(errno) + ")");
  if (S_ISREG(st.st_mode) || (folder_allowed && S_ISDIR(st.st_mode))) return;
  throw Error(path + ": cannot read " + what + ": it is " + kind_of(st.st_mode) + ", not a regular file" +
              (folder_allowed ? " or a folder" : ""));
}

}  // namespace hf
