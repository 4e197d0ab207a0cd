// A scalar volume for the anatomical slices: what the renderer needs of an image, and nothing of its file
// format (the NIfTI reader is in viewer/anatomy/).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace vxl {

struct Volume {
  std::string name;  // for messages (the file it came from)
  std::array<std::int64_t, 3> dims{0, 0, 0};
  std::vector<float> values;          // x fastest, then y, then z; already scaled to the image's units
  glm::dmat4 voxel_to_ras{1.0};       // voxel index (centre of voxel (i, j, k)) -> RAS mm
  std::array<float, 2> window{0, 1};  // the default grey range (values mapped to black and white)

  // The RAS corners of the volume's box (voxel faces, not centres): for fitting slices and the camera.
  std::array<glm::dvec3, 8> corners() const;
  glm::dvec3 ras_min() const;
  glm::dvec3 ras_max() const;
};

}  // namespace vxl
