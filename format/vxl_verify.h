// Full integrity check of a .vxl file (spec §7, `voxlines verify`): structure, every checksum, every
// padding byte, every order (a sorted permutation of its voxel's segments) and the streamline walk.
#pragma once

#include <string>

namespace vxl {

struct VerifyResult {
  bool valid = false;
  std::string problem;  // the first problem found, naming the file and byte offset; empty when valid
};

VerifyResult verify_vxl(const std::string& path);

}  // namespace vxl
