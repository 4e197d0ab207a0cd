#include "format/level_voxlines.h"

#include <array>

#include "format/base/error.h"
#include "format/vxl_levels.h"

namespace vxl {

LevelVoxlines::LevelVoxlines(const VxlFile& file, std::uint32_t level) : level_(level) {
  file.check_streamline_table();
  const auto strm = file.streamline_first_voxline();
  const auto voxlines = file.voxlines();
  const auto voxels = file.voxels();
  const std::uint32_t levels = file.level_count();
  std::vector<std::uint64_t> streamlines;  // the level's, in order
  for (std::uint64_t s = 0; s + 1 < strm.size(); ++s)
    if (streamline_depth(s, levels) >= level) streamlines.push_back(s);

  // Each voxel's voxlines of the level, counted, then listed in streamline order (as the voxel's list has them).
  first_.assign(voxels.size() + 1, 0);
  for (const std::uint64_t s : streamlines)
    for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
      file.check_voxline(j);
      ++first_[voxlines[j].voxel + 1];
    }
  for (std::size_t v = 0; v < voxels.size(); ++v) first_[v + 1] += first_[v];
  placed_.resize(first_.back());
  std::vector<std::uint64_t> next(first_.begin(), first_.end() - 1);
  for (const std::uint64_t s : streamlines) {
    const std::uint32_t depth = streamline_depth(s, levels);
    for (std::uint64_t j = strm[s]; j < strm[s + 1]; ++j) {
      PlacedVoxline& p = placed_[next[voxlines[j].voxel]++];
      p.streamline = static_cast<std::uint32_t>(s);
      p.own = voxlines[j].count_flags & kVoxlineCountMask;
      p.depth = depth;
      p.synthetic_first = (voxlines[j].count_flags & kVoxlineSyntheticFirst) != 0;
      p.first_of_streamline = j == strm[s];
      p.last_of_streamline = j + 1 == strm[s + 1];
    }
  }

  // Placed in each block: a voxline of depth d at that depth's cursor (spec §5.6, §5.12).
  const std::uint64_t voxt_at = file.find_section(section_id("VOXT"))->offset;
  for (std::size_t v = 0; v < voxels.size(); ++v) {
    const auto row = file.levels_of(v);
    std::array<std::uint64_t, kMaxLevels> cursor{}, end{};
    for (std::uint32_t d = 0; d < levels; ++d)
      cursor[d] = depth_first_vertex(row, d), end[d] = depth_end_vertex(voxels[v], row, d);
    for (std::uint64_t k = first_[v]; k < first_[v + 1]; ++k) {
      PlacedVoxline& p = placed_[k];
      if (cursor[p.depth] > end[p.depth] || p.vertices() > end[p.depth] - cursor[p.depth])
        fail_input(file.path(), voxt_at + sizeof(VoxelEntry) * v,
                   "the voxel's voxlines run past its vertex block (or a level's part of it)");
      p.first_vertex = voxels[v].vertex_first + cursor[p.depth];
      cursor[p.depth] += p.vertices();
    }
  }
}

}  // namespace vxl
