// `voxview --render OUT.png --turntable N`: N frames turning once around the vertical (superior) axis
// through the focus point, for figures and movies.
#pragma once

#include <string>

#include "camera.h"

namespace vxl::app {

// Frame `frame` of `frames`: the azimuth advanced by 360 * frame / frames degrees, all else kept, so
// frame 0 is `start` itself.
Camera turntable_camera(const Camera& start, int frame, int frames);

// Where frame `frame` of `frames` goes: OUT.png -> OUT_000.png, OUT_001.png, ... (at least three digits,
// more when needed so that the names sort in frame order; no extension: .png).
std::string turntable_frame_path(const std::string& png, int frame, int frames);

}  // namespace vxl::app
