// `voxlines verify` of a .vxlz package: every check the package spec asks of a reader (its §8, checksums included),
// every position chunk decoded, and the .vxl it unpacks to checked as `verify` checks a .vxl.
#pragma once

#include <string>

#include "format/vxl_verify.h"

namespace vxl {

// Unpacks `path` with unpack's defaults into a temporary .vxl ($TMPDIR, else /tmp: the unpacked file's size, removed
// at once) and verifies that. The problem names the package.
VerifyResult verify_vxlz(const std::string& path);

}  // namespace vxl
