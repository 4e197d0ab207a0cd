// The readers' first check on a path: only a regular file (or, for TRX, a directory) is read. Opening a
// FIFO for reading blocks until some writer opens it, so this is checked with stat() before any open().
#pragma once

#include <string>

namespace vxl {

// Throws vxl::Error (Input) naming `path` when it exists but is not a regular file (a FIFO, a device, a
// socket, or a directory unless `allow_directory`). A missing path is left to the open that follows,
// which reports it.
void require_regular_file(const std::string& path, bool allow_directory = false);

}  // namespace vxl
