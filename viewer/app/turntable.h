// `voxview --render OUT.png --turntable N`: N frames turning once around the vertical (superior) axis
// through the focus point, for figures and movies.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "viewer/render/camera.h"

namespace vxl::app {

// Frame `frame` of `frames`: the azimuth advanced by 360 * frame / frames degrees, all else kept, so
// frame 0 is `start` itself.
Camera turntable_camera(const Camera& start, int frame, int frames);

// `points` turned about the vertical axis through `pivot` as the turntable's frames turn the camera: a
// camera framing them all about `pivot` (Camera::frame_points_about) keeps every frame's picture whole.
std::vector<glm::dvec3> turntable_points(std::span<const glm::dvec3> points, const glm::dvec3& pivot, int frames);

// Where frame `frame` of `frames` goes: OUT.png -> OUT_000.png, OUT_001.png, ... (at least three digits,
// more when needed so that the names sort in frame order; no extension: .png).
std::string turntable_frame_path(const std::string& png, int frame, int frames);

}  // namespace vxl::app
