// What a renderer that draws a voxel's stored bytes as they are relies on, checked apart from drawing (spec
// §7): every order entry names a segment of the level's prefix of the block, order 0 names each segment once,
// and a packed block's voxline-end bits are set exactly where order 0 starts no segment, its reserved bits
// clear. The renderer's shaders clamp every index they read, so a file that fails these draws wrong lines but
// never reads outside a buffer; these checks say that it is damaged. `voxlines verify` checks all of this and
// more (the orders' sorting, the voxline walk).
#pragma once

#include <cstdint>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

// Level `level` of voxel `voxel` (`scratch` is reused between calls). Throws vxl::Error (Input) naming the
// file, the byte and the voxel.
void check_voxel_drawing(const VxlFile& file, std::uint32_t voxel, std::uint32_t level,
                         std::vector<std::uint8_t>& scratch);

}  // namespace vxl
