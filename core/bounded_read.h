// Reading untrusted input files whole, without trusting the file system: only regular files, with a size limit.
//
// A dataset's list or ground truth may be a link to /dev/zero (endless), a FIFO (blocks forever on open or read),
// a folder or a socket. read_regular_file opens without blocking (O_NONBLOCK, so a FIFO cannot stall the open),
// checks what it opened with fstat (no race between the check and the read), accepts only a regular file (links to
// one are followed: datasets often link their images), and reads at most `max_bytes`. Every refusal is an hf::Error
// naming the file, what it was expected to be, and the limit hit.
#pragma once

#include <cstddef>
#include <string>

namespace hf {

// Size limits for whole-file reads; each parser states its own line and entry limits beside its contract.
inline constexpr std::size_t kMaxTextFileBytes = std::size_t(256) << 20;   // lists, trajectories, configs, cameras
inline constexpr std::size_t kMaxImageFileBytes = std::size_t(256) << 20;  // one encoded colour or depth image
inline constexpr std::size_t kMaxModelFileBytes = std::size_t(8) << 30;    // meshes, point clouds, volumes

// The bytes of the regular file at `path` (at most max_bytes of them). `what` names the file's role in messages:
// "PATH: cannot read WHAT: it is a FIFO, not a regular file", "PATH: WHAT is larger than the 256 MiB limit".
std::string read_regular_file(const std::string& path, const std::string& what,
                              std::size_t max_bytes = kMaxTextFileBytes);

// The length of a line a line-based parser accepts ("PATH:LINE: expected a line of at most N bytes").
inline constexpr std::size_t kMaxLineBytes = 4096;

}  // namespace hf
