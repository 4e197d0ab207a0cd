// Which level of detail (.vxl spec §5.12) voxview uploads: the one --level names, else the finest whose GPU
// copy fits the GPU memory budget — --gpu-memory, or by default half of what the driver reports free, or on
// a driver that reports nothing (Mesa llvmpipe keeps its buffers in RAM) a quarter of the available memory.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "format/vxl_file.h"

namespace vxl::app {

struct SceneDetail {
  std::uint32_t level = 0;
  std::uint64_t span_texels = 0;  // the most texels a GPU texture span holds
  // The same for a level drawn whole, alone within the budget (headless: one renderer): the driver's limit, as when
  // full detail fits. Equal to span_texels unless paging chose smaller spans.
  std::uint64_t whole_span_texels = 0;
  std::uint64_t budget = 0;   // bytes
  std::string budget_source;  // where the budget comes from, for messages
  bool forced = false;        // --level chose the level
  std::uint32_t asked = 0;    // the level --level asked for (past the coarsest, the coarsest is drawn)
};

// The span size too: `span_texels` (--span-texels) when given, else the driver's texture-buffer limit when
// full detail fits the budget (the fewest spans: a draw of one span is the cheapest, its shader needs no
// span lookup), else kPagingSpanTexels, so that the budget can hold just the visible spans; raised to what
// the largest voxel needs, within the driver's limit. whole_span_texels: the first of these, for a level that one
// renderer draws whole within the budget. Needs a current GL context. Throws vxl::Error
// (Unsupported) when even the coarsest level does not fit.
SceneDetail choose_scene_detail(const std::vector<const VxlFile*>& files, std::optional<std::uint32_t> level,
                                std::optional<std::uint64_t> gpu_memory,
                                std::optional<std::uint64_t> span_texels = std::nullopt);

// The span size when paging: 4M texels, at most 64 MiB of positions and tables and 8 MiB of orders.
inline constexpr std::uint64_t kPagingSpanTexels = std::uint64_t(1) << 22;

// One line for the user when the scene is drawn at a coarse level; empty at full detail.
std::string describe_scene_detail(const SceneDetail& detail, std::uint32_t levels_in_files);

}  // namespace vxl::app
