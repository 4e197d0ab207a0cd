#include "viewer/render/line_lighting.h"

#include <algorithm>
#include <cmath>

namespace vxl::lighting {

glm::vec3 light_direction_eye() { return glm::normalize(glm::vec3(-0.5f, 0.5f, 1.0f)); }

glm::vec3 lit_colour(const glm::vec3& base, const glm::vec3& t, const glm::vec3& v) {
  const float lt = glm::dot(light_direction_eye(), t), vt = glm::dot(v, t);
  const float diffuse = std::sqrt(std::max(0.0f, 1.0f - lt * lt));
  const float specular =
      std::pow(std::max(0.0f, diffuse * std::sqrt(std::max(0.0f, 1.0f - vt * vt)) - lt * vt), kShininess);
  return base * (kAmbient + kDiffuse * diffuse) + glm::vec3(kSpecular * specular);
}

}  // namespace vxl::lighting
