// Outputs are never half-written: write to "<path>.tmp.<pid>" in the same folder, then rename over <path>.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>

namespace hf {

// Calls write(stream) on a temporary file beside `path`, flushes, checks the stream, then renames it to `path`.
// On any failure (exception from write, stream error, rename error) the temporary is removed, `path` is left as
// it was, and hf::Error is thrown naming the file.
void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                           bool binary = false);

// For writers that need a file name (cv::imwrite, PCL): calls write(tmp_path) and renames on success.
// The temporary keeps the extension of `path` so format-by-extension writers still work.
void write_path_atomically(const std::string& path, const std::function<void(const std::string& tmp_path)>& write);

}  // namespace hf
