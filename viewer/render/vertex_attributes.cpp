#include "viewer/render/vertex_attributes.h"

#include <limits>

#include "format/vxl_streamlines.h"

namespace vxl {

ValueSource find_value_set(const VxlFile& file, const std::string& name) {
  if (int k = file.vertex_values().find(name); k >= 0)
    return {ValueSource::Kind::Vertex, static_cast<std::uint32_t>(k)};
  if (int k = file.streamline_values().find(name); k >= 0)
    return {ValueSource::Kind::Streamline, static_cast<std::uint32_t>(k)};
  return {};
}

std::vector<float> vertex_attributes(const VxlFile& file, std::size_t file_index, const ValueSource& source,
                                     const SceneGroups* groups) {
  const std::uint64_t v = file.meta().vertex_count;
  std::vector<float> out(2 * v);
  const float none = std::numeric_limits<float>::quiet_NaN();
  const bool uniform_group = groups == nullptr || groups->uniform(file_index);
  const float constant_group = groups == nullptr ? 0.0f : static_cast<float>(groups->group_of(file_index, 0));
  if (source.kind == ValueSource::Kind::Vertex) {
    const std::span<const float> values = file.vertex_values().values(source.set);
    for (std::uint64_t i = 0; i < v; ++i) out[2 * i] = values[i];
  } else {
    for (std::uint64_t i = 0; i < v; ++i) out[2 * i] = none;
  }
  for (std::uint64_t i = 0; i < v; ++i) out[2 * i + 1] = constant_group;
  if (source.kind != ValueSource::Kind::Streamline && uniform_group) return out;

  // Per-streamline values or groups: every vertex of a voxline belongs to the streamline being walked.
  const std::span<const float> per_streamline = source.kind == ValueSource::Kind::Streamline
                                                    ? file.streamline_values().values(source.set)
                                                    : std::span<const float>{};
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& v) {
    const std::uint64_t end = v.first_vertex + v.own_points + (v.connected ? 1 : 0);
    const float group = uniform_group ? constant_group : static_cast<float>(groups->group_of(file_index, v.streamline));
    for (std::uint64_t i = v.first_vertex; i < end; ++i) {
      if (!per_streamline.empty()) out[2 * i] = per_streamline[v.streamline];
      out[2 * i + 1] = group;
    }
  };
  walk_streamlines(file, cb);
  return out;
}

}  // namespace vxl
