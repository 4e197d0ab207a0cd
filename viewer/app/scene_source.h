// Opens what the user gave voxview: a .vxl is memory-mapped as is; a TCK/TRK/TRX source is converted in
// memory first (into an unlinked temporary file that only the mapping keeps alive), with a hint on how
// to convert once for fast reopening.
#pragma once

#include <string>
#include <vector>

#include "format/vxl_file.h"
#include "viewer/app/viewer_options.h"

namespace vxl {
class Renderer;
struct RenderSettings;
}  // namespace vxl

namespace vxl::app {

// `tsf`: MRtrix track scalar files to attach to a source tractogram (refused for a .vxl / .vxlz, whose values
// were fixed at conversion). `verify`: before a .vxl is used, check it as `voxlines verify` does (every
// checksum, padding byte, order and table; O(file)), and refuse it (vxl::Error, Input) naming the first
// problem; a .vxlz's unpacked .vxl is checked the same way (the package's own checksums always are).
// Without it a .vxl gets only open()'s O(voxels) checks (spec §7), which do not read the checksums.
VxlFile open_scene(const std::string& path, double voxel_size_for_sources, const std::vector<std::string>& tsf = {},
                   bool verify = false);

// Opens every input of a scene (open_scene each; --tsf only with a single source input). Throws vxl::Error.
std::vector<VxlFile> open_scenes(const std::vector<std::string>& paths, double voxel_size_for_sources,
                                 const std::vector<std::string>& tsf, bool verify = false);
std::vector<const VxlFile*> pointers(const std::vector<VxlFile>& files);

// Refuses colour options the scene cannot honour, naming the file and what it has: --color scalar without
// values, an unknown --scalar, a --group that is no group of the scene (Usage); the same settings from a
// view file (`from_view_file`) are that file's error (Input).
void check_color_options(const std::string& path, const Renderer& renderer, const RenderSettings& settings,
                         const ViewFileSettings& from_view_file = {});

}  // namespace vxl::app
