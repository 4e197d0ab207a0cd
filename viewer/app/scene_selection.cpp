#include "viewer/app/scene_selection.h"

#include "format/level_voxlines.h"

namespace vxl::app {

SceneSelection select_in_scene(std::span<const VxlFile* const> files, const SelectionCriteria& criteria,
                               VoxelVoxlinesCache* indexes, std::span<const std::unique_ptr<VoxlineBoxes>> boxes) {
  SceneSelection out;
  out.level = criteria.level.value_or(0);
  for (std::size_t i = 0; i < files.size(); ++i) {
    const VxlFile* f = files[i];
    const VoxelVoxlines* index = indexes ? indexes->of(i) : nullptr;
    const LevelVoxlines* level = indexes && out.level > 0 ? &indexes->level(i, out.level) : nullptr;
    SelectionResult r = select_streamlines(*f, criteria, index, SelectionPath::Fastest,
                                           boxes.empty() ? nullptr : boxes[i].get(), level);
    out.streamlines_per_region.resize(r.streamlines_per_region.size(), 0);
    for (std::size_t i = 0; i < r.streamlines_per_region.size(); ++i)
      out.streamlines_per_region[i] += r.streamlines_per_region[i];
    out.selected += r.streamlines.size();
    out.total += f->meta().streamline_count;
    out.kept.push_back(std::move(r.streamlines));
  }
  out.groups = SceneGroups::selection(files, out.kept);
  return out;
}

}  // namespace vxl::app
