// What the line shader reads per vertex besides its position when colouring by value or by group: two
// 32-bit words, (value as float bits, streamline number in the scene). The group of a streamline is not
// here but in a table of one byte per streamline (Renderer), so that a new selection or grouping uploads
// that table alone. The words are made voxel by voxel as a span is uploaded, so that their cost follows
// what is drawn (a coarse level, the spans a GPU budget holds): each vertex's streamline comes from the
// voxel's list of voxlines (VoxelVoxlines), values from VVAL as it is or SVAL through the streamline.
#pragma once

#include <cstdint>
#include <string>

#include "format/voxel_voxlines.h"
#include "format/vxl_file.h"

namespace vxl {

struct ValueSource {
  enum class Kind { None, Vertex, Streamline };
  Kind kind = Kind::None;
  std::uint32_t set = 0;
};

// The set called `name` in `file`, per-vertex sets first; Kind::None when it has none of that name.
ValueSource find_value_set(const VxlFile& file, const std::string& name);

// Where one file's words come from.
struct AttributeSource {
  ValueSource values;
  std::uint32_t first_streamline = 0;    // the number of the file's streamline 0 in the scene
  const VoxelVoxlines* index = nullptr;  // the file's
  // Where the coarse levels' placements are kept (the file's number in it), or null: every level through `index`.
  VoxelVoxlinesCache* cache = nullptr;
  std::size_t file = 0;
};

// The first `vertices` vertices of voxel `voxel`'s block (a level's prefix, or all of it), 2 words each,
// into `out`: the bits of the value (a NaN where the source has none) and the streamline's number.
// Throws vxl::Error (Input) naming the voxel's table entry when its voxlines run past its block.
void voxel_attributes(const VxlFile& file, std::size_t voxel, const AttributeSource& source, std::uint32_t vertices,
                      std::uint32_t* out);

}  // namespace vxl
