// What the line shader reads per vertex besides its position when colouring by value or by group: two
// floats, (value, group index). Built on the CPU only when a colour mode or a group's opacity needs them,
// from the file's value sets (VVAL as it is; SVAL and groups spread to the vertices by a walk of the
// voxline table, spec §5.6).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "format/vxl_file.h"
#include "viewer/render/scene_groups.h"

namespace vxl {

struct ValueSource {
  enum class Kind { None, Vertex, Streamline };
  Kind kind = Kind::None;
  std::uint32_t set = 0;
};

// The set called `name` in `file`, per-vertex sets first; Kind::None when it has none of that name.
ValueSource find_value_set(const VxlFile& file, const std::string& name);

// 2 * vertex_count floats: per vertex its value (NaN where `source` is None) and its group index (0 when
// `groups` is null). `file_index` is the file's position in `groups`.
std::vector<float> vertex_attributes(const VxlFile& file, std::size_t file_index, const ValueSource& source,
                                     const SceneGroups* groups);

}  // namespace vxl
