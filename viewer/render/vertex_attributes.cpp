#include "viewer/render/vertex_attributes.h"

#include <bit>
#include <limits>
#include <vector>

#include "format/base/error.h"
#include "format/vxl_levels.h"

namespace vxl {

ValueSource find_value_set(const VxlFile& file, const std::string& name) {
  if (int k = file.vertex_values().find(name); k >= 0)
    return {ValueSource::Kind::Vertex, static_cast<std::uint32_t>(k)};
  if (int k = file.streamline_values().find(name); k >= 0)
    return {ValueSource::Kind::Streamline, static_cast<std::uint32_t>(k)};
  return {};
}

void voxel_attributes(const VxlFile& file, std::size_t voxel, const AttributeSource& source, std::uint32_t vertices,
                      std::uint32_t* out) {
  const VoxelEntry& v = file.voxels()[voxel];
  const std::uint32_t none = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::quiet_NaN());
  for (std::uint32_t i = 0; i < vertices; ++i) out[2 * i] = none, out[2 * i + 1] = source.first_streamline;
  const std::span<const float> per_vertex = source.values.kind == ValueSource::Kind::Vertex
                                                ? file.vertex_values().values(source.values.set)
                                                : std::span<const float>{};
  const std::span<const float> per_streamline = source.values.kind == ValueSource::Kind::Streamline
                                                    ? file.streamline_values().values(source.values.set)
                                                    : std::span<const float>{};
  if (!per_vertex.empty())
    for (std::uint32_t i = 0; i < vertices; ++i)
      out[2 * i] = std::bit_cast<std::uint32_t>(per_vertex[v.vertex_first + i]);

  // The voxel's voxlines lie in its block by depth, deepest first, then in streamline order (spec §5.4):
  // one cursor per depth, walked along the voxel's list.
  const std::uint32_t levels = file.level_count();
  const auto row = file.levels_of(voxel);
  std::vector<std::uint64_t> cursor(levels), end(levels);
  for (std::uint32_t d = 0; d < levels; ++d)
    cursor[d] = depth_first_vertex(row, d), end[d] = depth_end_vertex(v, row, d);
  for (const IndexedVoxline& e : source.index->of_voxel(voxel)) {
    const std::uint32_t d = e.depth();
    const std::uint64_t need = std::uint64_t(e.own()) + ((e.bits & IndexedVoxline::kLastOfStreamline) ? 0 : 1);
    if (d >= levels || cursor[d] > end[d] || need > end[d] - cursor[d])
      fail_input(file.path(), file.find_section(section_id("VOXT"))->offset + sizeof(VoxelEntry) * voxel,
                 "the voxel's voxlines run past its vertex block (or a level's part of it)");
    if (e.streamline >= file.meta().streamline_count)  // from the file's VXIX, unchecked until now
      fail_input(file.path(), file.find_section(section_id("VXIX"))->offset,
                 "voxel " + std::to_string(voxel) + "'s list names a streamline past the streamline count");
    const std::uint64_t first = cursor[d];
    cursor[d] += need;
    if (first >= vertices) continue;  // beyond the prefix drawn
    const std::uint32_t number = source.first_streamline + e.streamline;
    const std::uint32_t value =
        per_streamline.empty() ? none : std::bit_cast<std::uint32_t>(per_streamline[e.streamline]);
    for (std::uint64_t i = first; i < std::min<std::uint64_t>(first + need, vertices); ++i) {
      if (!per_streamline.empty()) out[2 * i] = value;
      out[2 * i + 1] = number;
    }
  }
}

}  // namespace vxl
