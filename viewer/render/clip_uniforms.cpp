#include "viewer/render/clip_uniforms.h"

#include <algorithm>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

#include "viewer/render/clip_planes.h"

namespace vxl {

int bind_clip_half_spaces(GLuint program, std::span<const glm::dvec4> half_spaces, const glm::dvec3& eye) {
  std::vector<glm::vec4> planes;
  for (const glm::dvec4& h : half_spaces) planes.push_back(glm::vec4(relative_to(h, eye)));
  const int clips = static_cast<int>(std::min<std::size_t>(planes.size(), kMaxClipDistances));
  if (clips > 0) glUniform4fv(glGetUniformLocation(program, "u_clip"), clips, glm::value_ptr(planes[0]));
  glUniform1i(glGetUniformLocation(program, "u_clip_count"), clips);
  enable_clip_distances(clips);
  return clips;
}

void enable_clip_distances(int n) {
#if VOXLINES_WEBGL
  (void)n;  // WebGL2 has no clip distances: the web viewer offers no slab or clip planes
#else
  for (int i = 0; i < kMaxClipDistances; ++i) {
    if (i < n)
      glEnable(GL_CLIP_DISTANCE0 + i);
    else
      glDisable(GL_CLIP_DISTANCE0 + i);
  }
#endif
}

}  // namespace vxl
