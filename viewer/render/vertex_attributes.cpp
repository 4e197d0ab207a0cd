#include "viewer/render/vertex_attributes.h"

#include <bit>
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

std::vector<std::uint32_t> vertex_attributes(const VxlFile& file, const ValueSource& source,
                                             std::uint32_t first_streamline) {
  const std::uint64_t v = file.meta().vertex_count;
  std::vector<std::uint32_t> out(2 * v, 0);
  if (source.kind == ValueSource::Kind::Vertex) {
    const std::span<const float> values = file.vertex_values().values(source.set);
    for (std::uint64_t i = 0; i < v; ++i) out[2 * i] = std::bit_cast<std::uint32_t>(values[i]);
  } else {
    const std::uint32_t none = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::quiet_NaN());
    for (std::uint64_t i = 0; i < v; ++i) out[2 * i] = none;
  }
  // Per-streamline values and numbers: every vertex of a voxline belongs to the streamline being walked.
  const std::span<const float> per_streamline = source.kind == ValueSource::Kind::Streamline
                                                    ? file.streamline_values().values(source.set)
                                                    : std::span<const float>{};
  WalkCallbacks cb;
  cb.voxline = [&](const VoxlineVisit& visit) {
    const std::uint64_t end = visit.first_vertex + visit.own_points + (visit.connected ? 1 : 0);
    const auto number = static_cast<std::uint32_t>(first_streamline + visit.streamline);
    for (std::uint64_t i = visit.first_vertex; i < end; ++i) {
      if (!per_streamline.empty()) out[2 * i] = std::bit_cast<std::uint32_t>(per_streamline[visit.streamline]);
      out[2 * i + 1] = number;
    }
  };
  walk_streamlines(file, cb);
  return out;
}

}  // namespace vxl
