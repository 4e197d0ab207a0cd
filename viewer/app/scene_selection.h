// A selection in every file of the scene (`voxlines select`'s rules): the kept streamlines are drawn as the
// focus, the others as context. Both are groups (scene_groups.h) whose opacity factors come from
// --focus-opacity and --context-opacity (or the panel), so focus and context are drawn in the one
// back-to-front pass of every mode and interleave correctly in depth.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "converter/selection/streamline_selection.h"
#include "converter/selection/voxline_boxes.h"
#include "viewer/render/scene_groups.h"

namespace vxl::app {

struct SceneSelection {
  SceneGroups groups;                                 // "selected" and "context"
  std::vector<std::vector<std::uint64_t>> kept;       // per file, its selected streamlines
  std::vector<std::uint64_t> streamlines_per_region;  // summed over the files (select_streamlines' order)
  std::uint64_t selected = 0, total = 0;
  // criteria.level: 0, or the level of detail whose streamlines alone are kept; right for pictures at that level or a
  // coarser one.
  std::uint32_t level = 0;
};

// `indexes` (one per file, or null), for selections repeated as regions move: each then reads the voxels
// its regions touch, not every file's whole voxline table, and with criteria.level only that level's voxlines
// (VoxelVoxlinesCache::level; the counts are then that level's); `boxes` (empty, or one per file) keeps what each
// selection learned of the voxels it touched for the next (voxline_boxes.h).
SceneSelection select_in_scene(std::span<const VxlFile* const> files, const SelectionCriteria& criteria,
                               VoxelVoxlinesCache* indexes = nullptr,
                               std::span<const std::unique_ptr<VoxlineBoxes>> boxes = {});

}  // namespace vxl::app
