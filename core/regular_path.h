// For readers that must hand a path to a library that opens it itself (an ifstream, GDAL, OpenNI2's file driver):
// what core/bounded_read.h's read_regular_file checks on the descriptor it opened, checked here on the path.
#pragma once

#include <string>

namespace hf {

// Refuses, without opening it, a path that (links followed) is a FIFO, a device or a socket, which would block the
// library forever or read endlessly, and a folder unless `folder_allowed` (GDAL takes shapefile folders). Throws
// hf::Error "PATH: cannot read WHAT: it is a FIFO, not a regular file", or "PATH: cannot read WHAT (No such file
// or directory)" for a missing path. A file swapped for a FIFO between this check and the library's own open is
// not caught; read_regular_file, which checks what it opened, is the reader to use wherever the bytes are ours.
void require_regular_path(const std::string& path, const std::string& what, bool folder_allowed = false);

}  // namespace hf
