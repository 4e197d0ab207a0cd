// `voxview FILE`: the interactive GLFW window with the Dear ImGui panel.
#pragma once

#include "viewer/app/viewer_options.h"

namespace vxl::app {

int run_window(const ViewerOptions& options);

}  // namespace vxl::app
