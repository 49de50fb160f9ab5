// Outputs that are never half-written and never written through a link we did not make.
//
// Every output goes to a temporary beside it that this process creates exclusively (O_CREAT | O_EXCL |
// O_NOFOLLOW, a name with 64 random bits, so nothing planted in advance can be opened), is flushed to disk
// (fsync) and renamed over the target. rename() replaces a link at the target instead of following it, so a
// planted "out/trajectory.txt -> ~/victim" is replaced by the real file and the victim is untouched. A crash or
// kill at any moment leaves either the old file or the new one (and at worst a hidden ".NAME.*.tmp" temporary),
// never a torn file.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace hf {

// Calls write(stream) on a fresh temporary beside `path`, flushes and fsyncs it, then renames it to `path` and
// syncs the folder. On any failure (exception from write, stream error, disk full, rename error, `path` is a
// folder) the temporary is removed, `path` is left as it was, and hf::Error is thrown naming `path`.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = false);

// For writers that insist on a file name (PCL): calls write(tmp_path) where tmp_path lies in a private folder
// (mode 0700, random name, made by this call beside `path`) and has the same file name as `path`, so
// format-by-extension writers still work. The result must be a regular file (not a link); it is fsynced and
// renamed to `path`, and the private folder is removed in every case.
void write_path_atomically(const std::string& path, const std::function<void(const std::string& tmp_path)>& write);

// Checks, before a long job starts, that `dir` can receive outputs: creates it (and its parents) when missing,
// requires a folder (an existing file, a dangling link or a folder of a pseudo file system such as /proc fail),
// and proves it writable by creating and removing an exclusive temporary there. Throws hf::Error naming `dir` and
// the reason.
void prepare_output_folder(const std::string& dir);

// A fresh, empty folder of this process's making beside `target` (same parent, so a rename can later move it onto
// `target`): "<parent>/.<name>.XXXXXX" from mkdtemp (mode 0700 until the caller changes it). Throws hf::Error
// naming `target` when the parent does not exist or is not writable.
std::string make_private_folder_beside(const std::string& target);

// Puts the finished folder `fresh` (from make_private_folder_beside(dir)) in place of `dir`: when `dir` exists
// the two are exchanged in one atomic step (renameat2 RENAME_EXCHANGE; where the file system lacks it, two
// renames), then the old contents, now under the temporary name, are removed without following links. Throws
// hf::Error naming `dir`; on failure `dir` is left as it was and `fresh` is removed.
void swap_folder_into_place(const std::string& fresh, const std::string& dir);

}  // namespace hf
