// `voxview FILE --render OUT.png`: one frame through EGL surfaceless (no X server), written with
// OpenImageIO; with --turntable N, N frames around the vertical axis.
#pragma once

#include "viewer_options.h"

namespace vxl::app {

int run_headless(const ViewerOptions& options);

// The camera voxview starts with for a scene: a saved view's (--camera), else framed on the scene's
// bounds, looking from `view` (or a default oblique view from the front-left-top).
Camera initial_camera(const glm::dvec3& lo, const glm::dvec3& hi, const ViewerOptions& options, double aspect);

}  // namespace vxl::app
