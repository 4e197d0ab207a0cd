// Full integrity check of a .vxl file (spec §7, `voxlines verify`): structure, every checksum, every
// padding byte, every order (a sorted permutation of its voxel's segments) and the streamline walk.
#pragma once

#include <string>

#include "format/base/error.h"
#include "format/vxl_file.h"

namespace vxl {

struct VerifyResult {
  bool valid = false;
  // What kind of problem: Input for a damaged or malformed file; Unsupported for a kind or version this reader
  // does not handle; Output when a package could not be unpacked to be checked.
  ErrorKind kind = ErrorKind::Input;
  std::string problem;  // the first problem found, naming the file and byte offset; empty when valid

  // The result of a check that `e` ended.
  static VerifyResult refused(const Error& e) { return {false, e.kind(), e.what()}; }
};

VerifyResult verify_vxl(const std::string& path);
// The same checks of a file already open (its errors name f.path()).
VerifyResult verify_vxl(const VxlFile& f);

}  // namespace vxl
