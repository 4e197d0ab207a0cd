// Opening a file that must be a regular one (the memory-mapped reader, the streamed TCK reader).
#pragma once

#include <string>

#include <sys/stat.h>

namespace vxl {

// Opens `path` read-only and returns its descriptor (the caller closes it), with its fstat() in `st`.
// O_NONBLOCK: opening a FIFO would otherwise wait for a writer; it has no effect on a regular file, and
// anything else is refused here. Throws vxl::Error (Input) naming `path` ("cannot open: ...", "cannot
// stat: ...", "not a regular file"), leaving nothing open.
int open_regular_file(const std::string& path, struct stat& st);

}  // namespace vxl
