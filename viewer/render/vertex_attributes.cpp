#include "viewer/render/vertex_attributes.h"

#include <cstring>
#include <limits>
#include <vector>

#include "format/base/error.h"
#include "format/base/float_bits.h"
#include "format/level_voxlines.h"
#include "format/vxl_levels.h"

namespace vxl {
namespace {

// The first level whose voxlines are placed for the whole file at once (and kept), from its own streamlines. On
// the 10M synthetic set, both cores, warm: level 4 took 0.05-0.06 s against 0.13-0.19 s through the voxels'
// lists (84M entries); level 3 about the same either way (0.11-0.17 s against 0.13 s); level 2 0.29 s against
// 0.22 s, its streamlines' voxlines spread over every page of VXLN.
constexpr std::uint32_t kFirstLevelPlacedOnce = 4;

}  // namespace

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
  const std::uint32_t none = float_bits(std::numeric_limits<float>::quiet_NaN());
  for (std::uint32_t i = 0; i < vertices; ++i) out[2 * i] = none, out[2 * i + 1] = source.first_streamline;
  const std::span<const float> per_vertex = source.values.kind == ValueSource::Kind::Vertex
                                                ? file.vertex_values().values(source.values.set)
                                                : std::span<const float>{};
  const std::span<const float> per_streamline = source.values.kind == ValueSource::Kind::Streamline
                                                    ? file.streamline_values().values(source.values.set)
                                                    : std::span<const float>{};
  if (!per_vertex.empty())
    for (std::uint32_t i = 0; i < vertices; ++i) out[2 * i] = float_bits(per_vertex[v.vertex_first + i]);

  // The voxel's voxlines, placed in its block through its list (spec §5.14): those of the coarsest level whose
  // prefix holds the vertices drawn, so that a coarse level's words cost its own vertices. The scratch is kept for
  // the thread's next voxel.
  const auto row = file.levels_of(voxel);
  std::uint32_t level = 0;
  while (level + 1 < file.level_count() && voxel_level(v, row, level + 1).vertex_count >= vertices) ++level;
  // A coarse enough level's voxlines are placed once for every voxel from its own streamlines (LevelVoxlines: a
  // 4096th of the file's at level 4), rather than each voxel's through its whole list.
  thread_local std::vector<std::uint8_t> ends;
  thread_local std::vector<PlacedVoxline> placed;
  std::span<const PlacedVoxline> voxlines;
  if (level >= kFirstLevelPlacedOnce && source.cache != nullptr) {
    voxlines = source.cache->level(source.file, level).of_voxel(voxel);
  } else {
    place_voxel_voxlines(file, *source.index, voxel, ends, placed, level);
    voxlines = placed;
  }
  for (const PlacedVoxline& p : voxlines) {
    const std::uint64_t first = p.first_vertex - v.vertex_first;
    if (first >= vertices) continue;  // beyond the prefix drawn
    const std::uint32_t number = source.first_streamline + p.streamline;
    const std::uint32_t value = per_streamline.empty() ? none : float_bits(per_streamline[p.streamline]);
    for (std::uint64_t i = first; i < std::min<std::uint64_t>(first + p.vertices(), vertices); ++i) {
      if (!per_streamline.empty()) out[2 * i] = value;
      out[2 * i + 1] = number;
    }
  }
}

}  // namespace vxl
