#include "viewer/render/modes/fullscreen_composite.h"

#include "viewer/render/clip_uniforms.h"
#include "viewer/render/line_pass.h"

namespace vxl {

void draw_fullscreen_composite(GLuint program, GLuint vao,
                               std::initializer_list<std::pair<const char*, GLuint>> textures) {
  enable_clip_distances(0);  // the composite writes no gl_ClipDistance
  glUseProgram(program);
  GLint unit = 0;
  for (const auto& [name, texture] : textures) {
    glActiveTexture(GL_TEXTURE0 + unit);
    glBindTexture(GL_TEXTURE_2D, texture);
    glUniform1i(glGetUniformLocation(program, name), unit++);
  }
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);  // a fullscreen triangle
  glActiveTexture(GL_TEXTURE0);
}

}  // namespace vxl
