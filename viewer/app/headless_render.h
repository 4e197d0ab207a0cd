// `voxview FILE --render OUT.png`: one frame through EGL surfaceless (no X server), written with
// OpenImageIO; with --turntable N, N frames around the vertical axis.
#pragma once

#include <span>

#include <glm/glm.hpp>

#include "viewer/render/camera.h"

#include "viewer/app/viewer_options.h"

namespace vxl::app {

int run_headless(const ViewerOptions& options);

// The camera voxview starts with for a scene: a saved view's (--camera), else looking from `view` (or a
// default oblique view from the front-left-top) with `points` (scene_framing.h) filling the window; with
// --turntable, every frame's picture whole, turning about the points' centre.
Camera initial_camera(std::span<const glm::dvec3> points, const ViewerOptions& options, double aspect);

}  // namespace vxl::app
