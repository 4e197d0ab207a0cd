// voxview's --include / --exclude / --ends-in: the streamlines `voxlines select` would keep, in every file
// of the scene, drawn as the focus; the others as context. Both are groups (scene_groups.h) whose opacity
// factors come from --focus-opacity and --context-opacity, so focus and context are drawn in the one
// back-to-front pass of every mode and interleave correctly in depth.
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "viewer/app/viewer_options.h"
#include "viewer/render/scene_groups.h"

namespace vxl::app {

// The selection's groups, or none when no region is given. Parses every region first (a bad one is a
// vxl::Error naming it, before any GL work) and prints how many streamlines were selected to stderr.
std::optional<SceneGroups> select_in_scene(std::span<const VxlFile* const> files, const ViewerOptions& options);

}  // namespace vxl::app
