// Opens what the user gave voxview: a .vxl is memory-mapped as is; a TCK/TRK/TRX source is converted in
// memory first (into an unlinked temporary file that only the mapping keeps alive), with a hint on how
// to convert once for fast reopening.
#pragma once

#include <string>

#include "vxl_file.h"

namespace vxl::app {

VxlFile open_scene(const std::string& path, double voxel_size_for_sources);

}  // namespace vxl::app
