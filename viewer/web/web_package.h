// A .vxlz package opened in the web page: unpacked as `voxlines unpack` unpacks it (converter/package/unpack.h),
// through Emscripten's in-memory file system, into the .vxl bytes the viewer opens.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "format/base/mapped_file.h"

namespace vxl::web {

// Whether `bytes` begin as a .vxlz package does (its magic, spec/vxlz-package-v2.md §2.1).
bool is_package(std::span<const std::uint8_t> bytes);

// Unpacks the package `package` (named `name` in errors) into a .vxl held in memory. The package is copied into
// the in-memory file system first and let go then, so that the memory holds it once while it is unpacked; nothing
// is left in the file system, also when the package is refused (vxl::Error, as unpack_vxlz throws it).
MappedFile unpack_package(MappedFile package, const std::string& name);

}  // namespace vxl::web
