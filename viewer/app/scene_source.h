// Opens what the user gave voxview: a .vxl is memory-mapped as is; a .vxlz is unpacked into a temporary
// .vxl; a source tractogram (readers/source_formats.h) is converted as `voxlines convert` converts it
// (converter/convert/source_to_vxl.h: in memory, or streamed through the temporary file when it is larger than the
// memory or --memory-limit) into a temporary .vxl that only the mapping keeps alive, with a hint on how to
// convert once for fast reopening.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "converter/convert/source_to_vxl.h"
#include "format/vxl_file.h"
#include "viewer/app/viewer_options.h"

namespace vxl {
class Renderer;
struct RenderSettings;
}  // namespace vxl

namespace vxl::app {

struct SceneSourceOptions {
  double voxel_size = 10.0;      // mm, for a source tractogram
  bool voxel_size_auto = false;  // chosen from the data instead (converter/convert/voxel_size_auto.h)
  // MRtrix track scalar files to attach to a source tractogram (refused for a .vxl / .vxlz, whose values were
  // fixed at conversion).
  std::vector<std::string> tsf;
  // Before a .vxl is used, check it as `voxlines verify` does (every checksum, padding byte, order and table;
  // O(file)), and refuse it (vxl::Error, Input) naming the first problem; a .vxlz's unpacked .vxl is checked
  // the same way (the package's own checksums always are). Without it a .vxl gets only open()'s O(voxels)
  // checks (spec §7), which do not read the checksums.
  bool verify = false;
  // --memory-limit: stream a source within this many bytes (as `voxlines convert --memory-limit`); 0: stream
  // a TCK only when converting it in memory would not fit in the available memory.
  std::uint64_t memory_limit = 0;
};
SceneSourceOptions scene_source_options(const ViewerOptions& options);

// Whether `path` is opened as it is, a .vxl or a .vxlz (any case), rather than converted as a source tractogram.
bool opens_without_conversion(const std::string& path);

struct OpenedScene {
  VxlFile file;
  std::optional<SourceConversionReport> conversion;  // for a source tractogram: how it was converted
};

// Opens one input. Throws vxl::Error.
OpenedScene open_scene(const std::string& path, const SceneSourceOptions& options);

// Opens every input of a scene (open_scene each; --tsf only with a single source input). Throws vxl::Error.
std::vector<VxlFile> open_scenes(const std::vector<std::string>& paths, const SceneSourceOptions& options);
std::vector<const VxlFile*> pointers(const std::vector<VxlFile>& files);

// Refuses colour options the scene cannot honour, naming the file and what it has: --color scalar without
// values, an unknown --scalar, a --group that is no group of the scene (Usage); the same settings from a
// view file (`from_view_file`) are that file's error (Input). `groups`: the names a --group may take when they are
// not yet the renderer's (a selection on its way: "selected" and "context"); empty: the renderer's.
void check_color_options(const std::string& path, const Renderer& renderer, const RenderSettings& settings,
                         const ViewFileSettings& from_view_file = {}, const std::vector<std::string>& groups = {});

}  // namespace vxl::app
