// What the line shader reads per vertex besides its position when colouring by value or by group: two
// 32-bit words, (value as float bits, streamline number in the scene). The group of a streamline is not
// here but in a table of one byte per streamline (Renderer), so that a new selection or grouping uploads
// that table alone and the per-vertex words stay: built on the CPU only when a colour mode or a group's
// opacity first needs them, from the file's value sets (VVAL as it is; SVAL and the streamline numbers
// spread to the vertices by a walk of the voxline table, spec §5.6).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "format/vxl_file.h"

namespace vxl {

struct ValueSource {
  enum class Kind { None, Vertex, Streamline };
  Kind kind = Kind::None;
  std::uint32_t set = 0;
};

// The set called `name` in `file`, per-vertex sets first; Kind::None when it has none of that name.
ValueSource find_value_set(const VxlFile& file, const std::string& name);

// 2 * vertex_count words: per vertex the bits of its value (a NaN where `source` is None) and
// `first_streamline` + the number of its streamline in the file.
std::vector<std::uint32_t> vertex_attributes(const VxlFile& file, const ValueSource& source,
                                             std::uint32_t first_streamline);

}  // namespace vxl
