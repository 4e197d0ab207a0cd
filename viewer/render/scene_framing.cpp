#include "viewer/render/scene_framing.h"

namespace vxl {

std::vector<glm::dvec3> framing_points(const SceneLayout& layout) {
  std::vector<glm::dvec3> points;
  points.reserve(layout.voxels().size() * 8);
  for (const VoxelDrawInfo& v : layout.voxels()) {
    const glm::dvec3 lo(v.tight_min), hi(v.tight_max);
    for (int corner = 0; corner < 8; ++corner)
      points.emplace_back(corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z);
  }
  return points;
}

}  // namespace vxl
