// The one rule for every output path (a .vxl, .vxlz, .tck, .tsf, .trx, .vtk, a PNG, a view or stats
// file). Outputs are written to a temporary file (unnamed, O_TMPFILE, where the file system allows) that is
// renamed into place when complete, and a rename replaces whatever
// has the name: a device node or a FIFO would be destroyed (as root, `--render /dev/null` made /dev/null a
// regular file), a symbolic link would be cut. So, before anything is written:
//   - no file at the path: it is created, in a folder that must exist;
//   - a regular file: it is replaced;
//   - a symbolic link: it is followed, and the rule applies to what it points to; the file pointed to is
//     replaced (or created), the link is kept;
//   - a directory, a FIFO, a device, a socket: refused (exit 5), never replaced.
#pragma once

#include <filesystem>
#include <string>

namespace vxl {

// The path the output is to be renamed to: `path` itself, or the file its symbolic links lead to.
// Throws vxl::Error (Output) naming `path` when the rule refuses it (or a link cannot be followed).
std::string output_target(const std::string& path);

// True when outputs `a` and `b` are one file: the same path once symbolic links, `.` and `..` are
// resolved, or, for files that exist, the same file under two names (a hard link). Throws what
// output_target throws.
bool same_output(const std::string& a, const std::string& b);

// The folder for temporary files: $TMPDIR when it is set, else /tmp. Throws vxl::Error (Output) naming the
// variable when it names no folder, rather than the library's bare "temp_directory_path" error.
std::filesystem::path temporary_folder();

}  // namespace vxl
