// Export of a .vxl back to the source streamlines, as a TCK file (Float32LE, RAS mm).
#pragma once

#include <string>

#include "vxl_file.h"

namespace vxl {

// Writes `out_path` atomically; the streamlines are those the converter read (spec §5.6), bit-exact for
// float32 sources. Throws vxl::Error.
void export_tck(const VxlFile& file, const std::string& out_path);

}  // namespace vxl
