// A .vxl that is only needed while it is mapped (voxview given a source or a .vxlz): written under a fresh
// temporary name, mapped, and removed at once, so that nothing is left behind, also when writing fails.
#pragma once

#include <functional>
#include <string>

#include "format/vxl_file.h"

namespace vxl {

struct TemporaryVxl {
  VxlFile file;
  std::string path;     // where it was written; already removed
  bool in_ram = false;  // the folder is a RAM file system (tmpfs): the mapped file takes memory
};

// Calls `write` with a fresh path "voxlines-XXXXXX-NAME.vxl" (NAME: the file name of `name`; mkstemps makes the
// name this call's alone, as an empty file that `write` replaces) in `dir` (empty: the system's temporary
// folder, $TMPDIR or else /tmp), opens what it wrote, named `name` (VxlFile::path(): in errors, and the scene's group
// of a file is its file name), and removes it: the mapping keeps the data. The file is
// removed also when `write` or the opening throws; the exception goes on. Throws vxl::Error (Output) when no
// temporary file can be made.
TemporaryVxl open_through_temporary_vxl(const std::string& name, const std::function<void(const std::string&)>& write,
                                        const std::string& dir = {});

}  // namespace vxl
