// The points a default view frames: the corners of every voxel's tight box (the box of its vertices), so
// that the picture fits the streamlines themselves rather than the scene's bounding box, which an
// oblique view shows much larger than the tractogram.
#pragma once

#include <vector>

#include <glm/glm.hpp>

#include "viewer/render/scene_layout.h"

namespace vxl {

std::vector<glm::dvec3> framing_points(const SceneLayout& layout);

}  // namespace vxl
