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
  std::uint64_t budget = 0;   // bytes
  std::string budget_source;  // where the budget comes from, for messages
  bool forced = false;        // --level chose the level
};

// Needs a current GL context when `gpu_memory` is not given (it asks the driver). Throws vxl::Error
// (Unsupported) when even the coarsest level does not fit.
SceneDetail choose_scene_detail(const std::vector<const VxlFile*>& files, std::optional<std::uint32_t> level,
                                std::optional<std::uint64_t> gpu_memory, std::uint64_t max_texels);

// The most texels a GPU texture span may hold: `wanted` (--span-texels), raised to what the largest voxel
// needs, within the driver's texture-buffer limit (needs a current GL context).
std::uint64_t span_texels(const std::vector<const VxlFile*>& files, std::uint64_t wanted);

// One line for the user when the scene is drawn at a coarse level; empty at full detail.
std::string describe_scene_detail(const SceneDetail& detail, std::uint32_t levels_in_files);

}  // namespace vxl::app
