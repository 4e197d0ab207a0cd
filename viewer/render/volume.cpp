#include "viewer/render/volume.h"

namespace vxl {

std::array<glm::dvec3, 8> Volume::corners() const {
  std::array<glm::dvec3, 8> out;
  for (int c = 0; c < 8; ++c) {
    const glm::dvec4 ijk((c & 1) ? dims[0] - 0.5 : -0.5, (c & 2) ? dims[1] - 0.5 : -0.5, (c & 4) ? dims[2] - 0.5 : -0.5,
                         1.0);
    out[c] = glm::dvec3(voxel_to_ras * ijk);
  }
  return out;
}

glm::dvec3 Volume::ras_min() const {
  glm::dvec3 lo(1e300);
  for (const glm::dvec3& p : corners()) lo = glm::min(lo, p);
  return lo;
}

glm::dvec3 Volume::ras_max() const {
  glm::dvec3 hi(-1e300);
  for (const glm::dvec3& p : corners()) hi = glm::max(hi, p);
  return hi;
}

}  // namespace vxl
