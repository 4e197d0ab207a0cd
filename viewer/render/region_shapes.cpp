#include "viewer/render/region_shapes.h"

#include <algorithm>

namespace vxl {

glm::vec3 region_shell_color(RegionShape::Role role) {
  switch (role) {
    case RegionShape::Role::Include: return {0.25f, 0.95f, 0.35f};
    case RegionShape::Role::Exclude: return {1.0f, 0.3f, 0.25f};
    case RegionShape::Role::EndsIn: return {0.3f, 0.55f, 1.0f};
  }
  return {1.0f, 1.0f, 1.0f};
}

float region_shell_alpha(float facing, bool active) {
  // Face-on the shell hides little of what lies behind it; towards the rim a ray crosses more of it.
  const float rim = 1.0f - std::clamp(facing, 0.0f, 1.0f);
  const float base = active ? 0.16f : 0.08f;
  return std::min(1.0f, base * (1.0f + 2.0f * rim * rim));
}

}  // namespace vxl
