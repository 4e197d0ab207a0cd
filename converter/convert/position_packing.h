// Packs the vertex blocks of spec §5.4 for a file with packed positions: each voxel's block quantised
// across its tight bounds, the voxline-end bit set where no segment starts, and the floats replaced by
// what the packed words decode to — so that the orders built from them afterwards are the orders of the
// positions the file holds (verify re-sorts the decoded positions and must find them sorted).
#pragma once

#include <cstdint>
#include <span>

#include "converter/convert/voxelize.h"
#include "format/vxl_layout.h"

namespace vxl {

// `voxels` hold vertex_first relative to `vertices` and `ends` (3 floats and one bit per vertex); `packed`
// gets one word per vertex. Tight bounds must be set. Spread over `threads` threads (0: all).
void pack_vertex_blocks(std::span<const VoxelEntry> voxels, std::span<float> vertices, const VoxlineEnds& ends,
                        std::span<std::uint32_t> packed, unsigned threads);

}  // namespace vxl
